// ----------------------------------------------------------------------------
// block_3d.geo -- internodes mesh: single elastic block, 3D
// ----------------------------------------------------------------------------
//
// Models : the block of hemisphere_on_block.geo alone, [-W,W]^2 x [-H,0], with
//          the same mesh refinement towards the origin on its top face z = 0.
//          Used to validate single-body solves: a Hertzian pressure
//          p(r) = p0 sqrt(1 - r^2/a^2) is applied on block_top, block_base is
//          clamped. The origin is a mesh node (embedded in the top face).
//
// Parameters (override with  -setnumber name value; lengths in model units):
//   level  refinement level (integer, may be negative to coarsen);
//          every mesh size below is multiplied by 2^-level          [0]
//   R      reference radius (radius of the indenter of the contact
//          problems; only used for the defaults below)               [1]
//   W      half-width of the block (x and y)                         [2 R]
//   H      height of the block                                       [2 R]
//   h_c    mesh size within distance r_c of the origin (level 0)     [R/15]
//   h_far  mesh size far from the origin (level 0)                   [R/2]
//   r_c    radius of the uniformly refined contact zone              [R/4]
//   d_far  distance from the origin where h_far is reached; the
//          size grows linearly from h_c at r_c to h_far at d_far     [2 R]
//
// Run :    gmsh -3 block_3d.geo -format msh41 -o block_3d.msh
//          gmsh -3 block_3d.geo -setnumber level 1 -format msh41 -o l1.msh
//
// Physical groups (P1: 4-node tetrahedra, 3-node triangles), section y = 0:
//
//                      block_top (z = 0, whole top face)
//   (-W,0) +-----------------------o-----------------------+ (W,0)
//          |                     origin                    |
//   block_ |                                               | block_sides
//   sides  |                 block (volume)                | (x = +-W,
//          |                                               |  y = +-W)
//  (-W,-H) +-----------------------------------------------+ (W,-H)
//                             block_base (z = -H)
//
// Boundary triangles are oriented with their right-hand normal pointing out
// of the block.
// ----------------------------------------------------------------------------

DefineConstant[
  level = {0, Name "Parameters/level"},
  R = {1, Name "Parameters/R"},
  W = {2 * R, Name "Parameters/W"},
  H = {2 * R, Name "Parameters/H"},
  h_c = {R / 15, Name "Parameters/h_c"},
  h_far = {R / 2, Name "Parameters/h_far"},
  r_c = {R / 4, Name "Parameters/r_c"},
  d_far = {2 * R, Name "Parameters/d_far"}
];

Geometry.AutoCoherence = 0; // never merge coincident points
s = 2 ^ (-level);           // size factor of this refinement level

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

// --- mesh size: refinement towards the origin --------------------------------------
Field[1] = Distance;
Field[1].PointsList = {p0};
Field[2] = Threshold;
Field[2].InField = 1;
Field[2].SizeMin = h_c * s;
Field[2].SizeMax = h_far * s;
Field[2].DistMin = r_c;
Field[2].DistMax = d_far;
Background Field = 2;

Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.Algorithm = 6;   // Frontal-Delaunay (surfaces)
Mesh.Algorithm3D = 1; // Delaunay
Mesh.ElementOrder = 1;

// --- physical groups ---------------------------------------------------------------
Physical Volume("block") = {v_block};
Physical Surface("block_top") = {s_top};
Physical Surface("block_base") = {s_base};
Physical Surface("block_sides") = {s_side1, s_side2, s_side3, s_side4};
