// ----------------------------------------------------------------------------
// two_hemispheres_on_block.geo -- internodes mesh: two elastic hemispheres side
//                                 by side on one elastic block, 3D
// ----------------------------------------------------------------------------
//
// Two contact pairs sharing a body: the hemispheres of hemisphere_on_block.geo
// (radius R, pole at (x_k, 0, gap), flat face at z = R + gap) centred at
// x = -c and x = +c above the block [-c-W, c+W] x [-W, W] x [-H, 0], whose top
// face has both contact points embedded. Each hemisphere is meshed as in
// hemisphere_on_block.geo, refined towards its pole; the block towards both.
// The geometry is mirror-symmetric about x = 0 (the meshes nearly so).
//
// Parameters (-setnumber name value): as hemisphere_on_block.geo, and
//   c      half the distance between the two poles                     [1.5 R]
//
// Physical groups: volumes left, right, block; surfaces left_contact,
// left_free, left_top, right_contact, right_free, right_top (as sphere_*),
// block_contact (the whole top face), block_base, block_sides.
// ----------------------------------------------------------------------------

DefineConstant[
  level = {0, Name "Parameters/level"},
  R = {1, Name "Parameters/R"},
  gap = {0, Name "Parameters/gap"},
  c = {1.5 * R, Name "Parameters/c"},
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

// --- block [-c-W, c+W] x [-W,W] x [-H,0], both contact points embedded in its top ---
pA = newp; Point(pA) = {-c, 0, 0};
pB = newp; Point(pB) = {c, 0, 0};
b1 = newp; Point(b1) = {-c-W, -W, -H};
b2 = newp; Point(b2) = { c+W, -W, -H};
b3 = newp; Point(b3) = { c+W,  W, -H};
b4 = newp; Point(b4) = {-c-W,  W, -H};
t1 = newp; Point(t1) = {-c-W, -W, 0};
t2 = newp; Point(t2) = { c+W, -W, 0};
t3 = newp; Point(t3) = { c+W,  W, 0};
t4 = newp; Point(t4) = {-c-W,  W, 0};
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
cl = newll; Curve Loop(cl) = {-lb4, -lb3, -lb2, -lb1};
s_base = news; Plane Surface(s_base) = {cl};
cl = newll; Curve Loop(cl) = {lt1, lt2, lt3, lt4};
s_top = news; Plane Surface(s_top) = {cl};
Point{pA, pB} In Surface{s_top};
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

// --- left hemisphere: lower half of the sphere of radius R centred at (-c,0,R+gap) ---
// curved surface = 4 three-sided patches around the pole (theta < theta_c)
//                + 4 four-sided patches (theta_c < theta < 90 deg)
zc = R + gap;                  // centre / flat face height
zl = zc - R * Cos(th);         // height of the latitude circle theta = theta_c
pC_left = newp; Point(pC_left) = {-c, 0, zc};
pP_left = newp; Point(pP_left) = {-c, 0, gap};
pL_left = newp; Point(pL_left) = {-c, 0, zl};
For i In {0:3}
  L_left[i] = newp; Point(L_left[i]) = {-c + R * Sin(th) * Cos(i * Pi / 2), R * Sin(th) * Sin(i * Pi / 2), zl};
  E_left[i] = newp; Point(E_left[i]) = {-c + R * Cos(i * Pi / 2), R * Sin(i * Pi / 2), zc};
EndFor
For i In {0:3}
  j = (i + 1) % 4;
  lat_left[i] = newl; Circle(lat_left[i]) = {L_left[i], pL_left, L_left[j]};   // latitude theta_c
  eq_left[i] = newl; Circle(eq_left[i]) = {E_left[i], pC_left, E_left[j]};     // equator (top rim)
  mer_left[i] = newl; Circle(mer_left[i]) = {L_left[i], pC_left, E_left[i]};   // meridian theta_c..90
  pm_left[i] = newl; Circle(pm_left[i]) = {pP_left, pC_left, L_left[i]};       // meridian pole..theta_c
EndFor
For i In {0:3}
  j = (i + 1) % 4;
  cl = newll; Curve Loop(cl) = {pm_left[j], -lat_left[i], -pm_left[i]};
  cap_left[i] = news; Surface(cap_left[i]) = {cl} In Sphere {pC_left};
  cl = newll; Curve Loop(cl) = {lat_left[i], mer_left[j], -eq_left[i], -mer_left[i]};
  ring_left[i] = news; Surface(ring_left[i]) = {cl} In Sphere {pC_left};
EndFor
cl = newll; Curve Loop(cl) = {eq_left[0], eq_left[1], eq_left[2], eq_left[3]};
s_flat_left = news; Plane Surface(s_flat_left) = {cl};
sl = newsl; Surface Loop(sl) = {cap_left[], ring_left[], s_flat_left};
v_sphere_left = newv; Volume(v_sphere_left) = {sl};


// --- right hemisphere: lower half of the sphere of radius R centred at (c,0,R+gap) ---
// curved surface = 4 three-sided patches around the pole (theta < theta_c)
//                + 4 four-sided patches (theta_c < theta < 90 deg)
zc = R + gap;                  // centre / flat face height
zl = zc - R * Cos(th);         // height of the latitude circle theta = theta_c
pC_right = newp; Point(pC_right) = {c, 0, zc};
pP_right = newp; Point(pP_right) = {c, 0, gap};
pL_right = newp; Point(pL_right) = {c, 0, zl};
For i In {0:3}
  L_right[i] = newp; Point(L_right[i]) = {c + R * Sin(th) * Cos(i * Pi / 2), R * Sin(th) * Sin(i * Pi / 2), zl};
  E_right[i] = newp; Point(E_right[i]) = {c + R * Cos(i * Pi / 2), R * Sin(i * Pi / 2), zc};
EndFor
For i In {0:3}
  j = (i + 1) % 4;
  lat_right[i] = newl; Circle(lat_right[i]) = {L_right[i], pL_right, L_right[j]};   // latitude theta_c
  eq_right[i] = newl; Circle(eq_right[i]) = {E_right[i], pC_right, E_right[j]};     // equator (top rim)
  mer_right[i] = newl; Circle(mer_right[i]) = {L_right[i], pC_right, E_right[i]};   // meridian theta_c..90
  pm_right[i] = newl; Circle(pm_right[i]) = {pP_right, pC_right, L_right[i]};       // meridian pole..theta_c
EndFor
For i In {0:3}
  j = (i + 1) % 4;
  cl = newll; Curve Loop(cl) = {pm_right[j], -lat_right[i], -pm_right[i]};
  cap_right[i] = news; Surface(cap_right[i]) = {cl} In Sphere {pC_right};
  cl = newll; Curve Loop(cl) = {lat_right[i], mer_right[j], -eq_right[i], -mer_right[i]};
  ring_right[i] = news; Surface(ring_right[i]) = {cl} In Sphere {pC_right};
EndFor
cl = newll; Curve Loop(cl) = {eq_right[0], eq_right[1], eq_right[2], eq_right[3]};
s_flat_right = news; Plane Surface(s_flat_right) = {cl};
sl = newsl; Surface Loop(sl) = {cap_right[], ring_right[], s_flat_right};
v_sphere_right = newv; Volume(v_sphere_right) = {sl};


// --- mesh size: each hemisphere refined towards its pole, the block towards both ---
Field[1] = Distance;
Field[1].PointsList = {pP_left};
Field[2] = Distance;
Field[2].PointsList = {pP_right};
Field[3] = Distance;
Field[3].PointsList = {pA, pB};
For k In {0:2}
  Field[4 + k] = Threshold;
  Field[4 + k].InField = 1 + k;
  Field[4 + k].SizeMin = h_c * s;
  Field[4 + k].SizeMax = h_far * s;
  Field[4 + k].DistMin = r_c;
  Field[4 + k].DistMax = d_far;
EndFor
Field[6].SizeMin = block_ratio * h_c * s;
Field[6].SizeMax = block_ratio * h_far * s;
Field[7] = Restrict;
Field[7].InField = 4;
Field[7].VolumesList = {v_sphere_left};
Field[7].SurfacesList = {cap_left[], ring_left[], s_flat_left};
Field[7].CurvesList = {lat_left[], eq_left[], mer_left[], pm_left[]};
Field[7].PointsList = {pP_left, L_left[], E_left[]};
Field[8] = Restrict;
Field[8].InField = 5;
Field[8].VolumesList = {v_sphere_right};
Field[8].SurfacesList = {cap_right[], ring_right[], s_flat_right};
Field[8].CurvesList = {lat_right[], eq_right[], mer_right[], pm_right[]};
Field[8].PointsList = {pP_right, L_right[], E_right[]};
Field[9] = Restrict;
Field[9].InField = 6;
Field[9].VolumesList = {v_block};
Field[9].SurfacesList = {s_base, s_top, s_side1, s_side2, s_side3, s_side4};
Field[9].CurvesList = {lb1, lb2, lb3, lb4, lt1, lt2, lt3, lt4, lv1, lv2, lv3, lv4};
Field[9].PointsList = {pA, pB, b1, b2, b3, b4, t1, t2, t3, t4};
Field[10] = Min;
Field[10].FieldsList = {7, 8, 9};
Background Field = 10;

Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.Algorithm = 6;   // Frontal-Delaunay (surfaces)
Mesh.Algorithm3D = 1; // Delaunay
Mesh.ElementOrder = 1;

// --- physical groups ---------------------------------------------------------------
Physical Volume("left") = {v_sphere_left};
Physical Volume("right") = {v_sphere_right};
Physical Volume("block") = {v_block};
Physical Surface("left_contact") = {cap_left[]};
Physical Surface("left_free") = {ring_left[]};
Physical Surface("left_top") = {s_flat_left};
Physical Surface("right_contact") = {cap_right[]};
Physical Surface("right_free") = {ring_right[]};
Physical Surface("right_top") = {s_flat_right};
Physical Surface("block_contact") = {s_top};
Physical Surface("block_base") = {s_base};
Physical Surface("block_sides") = {s_side1, s_side2, s_side3, s_side4};
