// ----------------------------------------------------------------------------
// hemisphere_on_block.geo -- internodes mesh: 3D Hertz contact,
//                            elastic hemisphere pressed onto an elastic block
// ----------------------------------------------------------------------------
//
// Models : the lower half of a sphere of radius R centred at (0,0,R+gap),
//          i.e. its pole (lowest point) is at (0,0,gap) and its flat cut face
//          at z = R + gap, sitting on the block [-W,W]^2 x [-H,0] whose top
//          face z = 0 contains the origin. With gap = 0 the two bodies touch
//          at the origin only; gap < 0 is an initial overlap. The two bodies
//          are independent meshes (no shared nodes, not even at the origin).
//          A displacement is imposed on sphere_top, block_base is clamped;
//          the Hertz contact radius is a ~ 0.1 R.
//          The pole of the sphere and the origin of the block top face are
//          mesh nodes.
//
// Parameters (override with  -setnumber name value; lengths in model units):
//   level    refinement level (integer, may be negative to coarsen);
//            every mesh size below is multiplied by 2^-level        [0]
//   R        sphere radius                                           [1]
//   gap      height of the pole above the block top (neg. = overlap) [0]
//   W        half-width of the block (x and y)                       [2 R]
//   H        height of the block                                     [2 R]
//   theta_c  polar angle (degrees, from the pole, 0 < theta_c < 90)
//            bounding sphere_contact; the rest of the curved
//            surface is sphere_free                                  [45]
//   h_c      mesh size in the contact zone, distance < r_c from the
//            origin / the pole (level 0)                             [R/15]
//   h_far    mesh size far from the contact point (level 0)          [R/2]
//   r_c      radius of the uniformly refined contact zone            [R/4]
//   d_far    distance from the contact point where h_far is
//            reached; linear growth from h_c at r_c                  [2 R]
//   block_ratio  block sizes = block_ratio * the sizes above, which
//            then apply to the hemisphere only (a coarser block
//            is the stable choice when the block is the stiff
//            primary body: see the README, "Choosing the primary") [1]
//
// Run :    gmsh -3 hemisphere_on_block.geo -format msh41 -o hob.msh
//          gmsh -3 hemisphere_on_block.geo -setnumber level 1 -setnumber gap -0.01 -o hob_l1.msh
//
// Physical groups (P1: 4-node tetrahedra, 3-node triangles), section y = 0:
//
//                           sphere_top (z = R + gap, flat disc)
//                 +---------------------------------+
//                  \                               /
//      sphere_free  \           sphere            /  sphere_free
//      (theta>theta_c)`.       (volume)         .'
//                        `-.               .-'
//                           `--._______.--'   <- sphere_contact (theta<theta_c)
//                                  o pole (0,0,gap)
//   +---------------------------------o---------------------------------+ z=0
//   |                        block_contact (whole top face)             |
//   |                                                                   |
//   | block_sides (x = +-W,                                             |
//   |  y = +-W)                     block (volume)                      |
//   |                                                                   |
//   +-------------------------------------------------------------------+ z=-H
//                               block_base
//
// Boundary triangles are oriented with their right-hand normal pointing out
// of their body.
// ----------------------------------------------------------------------------

DefineConstant[
  level = {0, Name "Parameters/level"},
  R = {1, Name "Parameters/R"},
  gap = {0, Name "Parameters/gap"},
  W = {2 * R, Name "Parameters/W"},
  H = {2 * R, Name "Parameters/H"},
  theta_c = {45, Name "Parameters/theta_c"},
  h_c = {R / 15, Name "Parameters/h_c"},
  h_far = {R / 2, Name "Parameters/h_far"},
  r_c = {R / 4, Name "Parameters/r_c"},
  d_far = {2 * R, Name "Parameters/d_far"},
  block_ratio = {1, Name "Parameters/block_ratio"}
];

Geometry.AutoCoherence = 0; // never merge coincident points (bodies are disjoint)
s = 2 ^ (-level);           // size factor of this refinement level
th = theta_c * Pi / 180;

// --- block [-W,W]^2 x [-H,0], origin embedded in the top face --------------------
p0 = newp; Point(p0) = {0, 0, 0};
b1 = newp; Point(b1) = {-W, -W, -H};
b2 = newp; Point(b2) = { W, -W, -H};
b3 = newp; Point(b3) = { W,  W, -H};
b4 = newp; Point(b4) = {-W,  W, -H};
t1 = newp; Point(t1) = {-W, -W, 0};
t2 = newp; Point(t2) = { W, -W, 0};
t3 = newp; Point(t3) = { W,  W, 0};
t4 = newp; Point(t4) = {-W,  W, 0};
lb1 = newl; Line(lb1) = {b1, b2};
lb2 = newl; Line(lb2) = {b2, b3};
lb3 = newl; Line(lb3) = {b3, b4};
lb4 = newl; Line(lb4) = {b4, b1};
lt1 = newl; Line(lt1) = {t1, t2};
lt2 = newl; Line(lt2) = {t2, t3};
lt3 = newl; Line(lt3) = {t3, t4};
lt4 = newl; Line(lt4) = {t4, t1};
lv1 = newl; Line(lv1) = {b1, t1};
lv2 = newl; Line(lv2) = {b2, t2};
lv3 = newl; Line(lv3) = {b3, t3};
lv4 = newl; Line(lv4) = {b4, t4};
// loops are counter-clockwise seen from outside (outward right-hand normal)
cl = newll; Curve Loop(cl) = {-lb4, -lb3, -lb2, -lb1};
s_base = news; Plane Surface(s_base) = {cl};
cl = newll; Curve Loop(cl) = {lt1, lt2, lt3, lt4};
s_top = news; Plane Surface(s_top) = {cl};
Point{p0} In Surface{s_top};
cl = newll; Curve Loop(cl) = {lb1, lv2, -lt1, -lv1};
s_side1 = news; Plane Surface(s_side1) = {cl};
cl = newll; Curve Loop(cl) = {lb2, lv3, -lt2, -lv2};
s_side2 = news; Plane Surface(s_side2) = {cl};
cl = newll; Curve Loop(cl) = {lb3, lv4, -lt3, -lv3};
s_side3 = news; Plane Surface(s_side3) = {cl};
cl = newll; Curve Loop(cl) = {lb4, lv1, -lt4, -lv4};
s_side4 = news; Plane Surface(s_side4) = {cl};
sl = newsl; Surface Loop(sl) = {s_base, s_top, s_side1, s_side2, s_side3, s_side4};
v_block = newv; Volume(v_block) = {sl};

// --- hemisphere: lower half of the sphere of radius R centred at (0,0,R+gap) ---
// curved surface = 4 three-sided patches around the pole (theta < theta_c)
//                + 4 four-sided patches (theta_c < theta < 90 deg)
zc = R + gap;                  // centre / flat face height
zl = zc - R * Cos(th);         // height of the latitude circle theta = theta_c
pC = newp; Point(pC) = {0, 0, zc};
pP = newp; Point(pP) = {0, 0, gap};
pL = newp; Point(pL) = {0, 0, zl};
For i In {0:3}
  L[i] = newp; Point(L[i]) = {R * Sin(th) * Cos(i * Pi / 2), R * Sin(th) * Sin(i * Pi / 2), zl};
  E[i] = newp; Point(E[i]) = {R * Cos(i * Pi / 2), R * Sin(i * Pi / 2), zc};
EndFor
For i In {0:3}
  j = (i + 1) % 4;
  lat[i] = newl; Circle(lat[i]) = {L[i], pL, L[j]};   // latitude theta_c
  eq[i] = newl; Circle(eq[i]) = {E[i], pC, E[j]};     // equator (top rim)
  mer[i] = newl; Circle(mer[i]) = {L[i], pC, E[i]};   // meridian theta_c..90
  pm[i] = newl; Circle(pm[i]) = {pP, pC, L[i]};       // meridian pole..theta_c
EndFor
For i In {0:3}
  j = (i + 1) % 4;
  cl = newll; Curve Loop(cl) = {pm[j], -lat[i], -pm[i]};
  cap[i] = news; Surface(cap[i]) = {cl} In Sphere {pC};
  cl = newll; Curve Loop(cl) = {lat[i], mer[j], -eq[i], -mer[i]};
  ring[i] = news; Surface(ring[i]) = {cl} In Sphere {pC};
EndFor
cl = newll; Curve Loop(cl) = {eq[0], eq[1], eq[2], eq[3]};
s_flat = news; Plane Surface(s_flat) = {cl};
sl = newsl; Surface Loop(sl) = {cap[], ring[], s_flat};
v_sphere = newv; Volume(v_sphere) = {sl};

// --- mesh size: refinement towards the contact point -------------------------------
// Each body's sizes are restricted to its own entities, so the block can be coarser.
Field[1] = Distance;
Field[1].PointsList = {p0, pP};
Field[2] = Threshold;              // hemisphere
Field[2].InField = 1;
Field[2].SizeMin = h_c * s;
Field[2].SizeMax = h_far * s;
Field[2].DistMin = r_c;
Field[2].DistMax = d_far;
Field[3] = Threshold;              // block (block_ratio x coarser)
Field[3].InField = 1;
Field[3].SizeMin = block_ratio * h_c * s;
Field[3].SizeMax = block_ratio * h_far * s;
Field[3].DistMin = r_c;
Field[3].DistMax = d_far;
Field[4] = Restrict;
Field[4].InField = 2;
Field[4].VolumesList = {v_sphere};
Field[4].SurfacesList = {cap[], ring[], s_flat};
Field[4].CurvesList = {lat[], eq[], mer[], pm[]};
Field[4].PointsList = {pP, L[], E[]};
Field[5] = Restrict;
Field[5].InField = 3;
Field[5].VolumesList = {v_block};
Field[5].SurfacesList = {s_base, s_top, s_side1, s_side2, s_side3, s_side4};
Field[5].CurvesList = {lb1, lb2, lb3, lb4, lt1, lt2, lt3, lt4, lv1, lv2, lv3, lv4};
Field[5].PointsList = {p0, b1, b2, b3, b4, t1, t2, t3, t4};
Field[6] = Min;
Field[6].FieldsList = {4, 5};
Background Field = 6;

Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.Algorithm = 6;   // Frontal-Delaunay (surfaces)
Mesh.Algorithm3D = 1; // Delaunay
Mesh.ElementOrder = 1;

// --- physical groups ---------------------------------------------------------------
Physical Volume("sphere") = {v_sphere};
Physical Volume("block") = {v_block};
Physical Surface("sphere_contact") = {cap[]};
Physical Surface("sphere_free") = {ring[]};
Physical Surface("sphere_top") = {s_flat};
Physical Surface("block_contact") = {s_top};
Physical Surface("block_base") = {s_base};
Physical Surface("block_sides") = {s_side1, s_side2, s_side3, s_side4};
