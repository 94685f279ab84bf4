// ----------------------------------------------------------------------------
// stack_3d.geo -- internodes mesh: three blocks stacked, 3D, each meshed with
//                 its own size: two flat interfaces, two contact pairs,
//                 neither interface mesh matching (3D version of stack_2d.geo)
// ----------------------------------------------------------------------------
//
// Models : bottom [0,L]^2 x [0,H_b], middle [0,L]^2 x [H_b, H_b+H_m], top
//          [0,L]^2 x [H_b+H_m, H_b+H_m+H_t]: three separate meshes (no shared
//          nodes). On rollers on the faces x = 0 and y = 0 of every block and on
//          the bottom block's base, the top block's top pushed down, the stack
//          is in uniform uniaxial stress: each block's exact displacement is
//          linear, which P1 represents exactly (validation/multi_body.py).
//          Every mesh size is uniform per block (point sizes).
//
// Parameters (-setnumber name value):
//   level            every mesh size is multiplied by 2^-level          [0]
//   L                width of the blocks (x and y)                       [1]
//   H_b, H_m, H_t    heights of the bottom, middle, top block    [0.6, 0.5, 0.4]
//   h_b, h_m, h_t    mesh sizes of the bottom, middle, top block
//                                                           [1/5, 1/7, 1/4]
//
// Run :    gmsh -3 stack_3d.geo -format msh41 -o stack_3d.msh
//
// Physical groups: volumes bottom, middle, top; for each block B the faces
//   B_x0 (x = 0), B_y0 (y = 0),
//   B_x1 (x = L), B_y1 (y = L), and the horizontal faces
//   bottom_base, bottom_top, middle_bottom, middle_top, top_bottom,
//   top_load (z = 0, H_b, H_b, H_b+H_m, H_b+H_m, H_b+H_m+H_t), as in
//   stack_2d.geo.
// ----------------------------------------------------------------------------

DefineConstant[
  level = {0, Name "Parameters/level"},
  L = {1, Name "Parameters/L"},
  H_b = {0.6, Name "Parameters/H_b"},
  H_m = {0.5, Name "Parameters/H_m"},
  H_t = {0.4, Name "Parameters/H_t"},
  h_b = {1 / 5, Name "Parameters/h_b"},
  h_m = {1 / 7, Name "Parameters/h_m"},
  h_t = {1 / 4, Name "Parameters/h_t"}
];

Geometry.AutoCoherence = 0; // never merge coincident points (bodies are disjoint)
f = 2 ^ (-level);

// One block [0,L]^2 x [z0, z0 + h], mesh size lc (as geo/two_blocks_3d.geo's
// MakeBlock): faces low (z = z0), high (z = z0 + h) and the sides s_y0, s_x1,
// s_y1, s_x0; every loop counter-clockwise seen from outside (outward normal).
Macro OneBlock
  b1 = newp; Point(b1) = {0, 0, z0, lc};
  b2 = newp; Point(b2) = {L, 0, z0, lc};
  b3 = newp; Point(b3) = {L, L, z0, lc};
  b4 = newp; Point(b4) = {0, L, z0, lc};
  t1 = newp; Point(t1) = {0, 0, z0 + h, lc};
  t2 = newp; Point(t2) = {L, 0, z0 + h, lc};
  t3 = newp; Point(t3) = {L, L, z0 + h, lc};
  t4 = newp; Point(t4) = {0, L, z0 + h, lc};
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
  low = news; Plane Surface(low) = {cl};
  cl = newll; Curve Loop(cl) = {lt1, lt2, lt3, lt4};
  high = news; Plane Surface(high) = {cl};
  cl = newll; Curve Loop(cl) = {lb1, lv2, -lt1, -lv1};
  s_y0 = news; Plane Surface(s_y0) = {cl};
  cl = newll; Curve Loop(cl) = {lb2, lv3, -lt2, -lv2};
  s_x1 = news; Plane Surface(s_x1) = {cl};
  cl = newll; Curve Loop(cl) = {lb3, lv4, -lt3, -lv3};
  s_y1 = news; Plane Surface(s_y1) = {cl};
  cl = newll; Curve Loop(cl) = {lb4, lv1, -lt4, -lv4};
  s_x0 = news; Plane Surface(s_x0) = {cl};
  sl = newsl; Surface Loop(sl) = {low, high, s_y0, s_x1, s_y1, s_x0};
  vol = newv; Volume(vol) = {sl};
Return

z0 = 0; h = H_b; lc = h_b * f;
Call OneBlock;
Physical Volume("bottom") = {vol};
Physical Surface("bottom_base") = {low};
Physical Surface("bottom_top") = {high};
Physical Surface("bottom_y0") = {s_y0};
Physical Surface("bottom_x1") = {s_x1};
Physical Surface("bottom_y1") = {s_y1};
Physical Surface("bottom_x0") = {s_x0};

z0 = H_b; h = H_m; lc = h_m * f;
Call OneBlock;
Physical Volume("middle") = {vol};
Physical Surface("middle_bottom") = {low};
Physical Surface("middle_top") = {high};
Physical Surface("middle_y0") = {s_y0};
Physical Surface("middle_x1") = {s_x1};
Physical Surface("middle_y1") = {s_y1};
Physical Surface("middle_x0") = {s_x0};

z0 = H_b + H_m; h = H_t; lc = h_t * f;
Call OneBlock;
Physical Volume("top") = {vol};
Physical Surface("top_bottom") = {low};
Physical Surface("top_load") = {high};
Physical Surface("top_y0") = {s_y0};
Physical Surface("top_x1") = {s_x1};
Physical Surface("top_y1") = {s_y1};
Physical Surface("top_x0") = {s_x0};

Mesh.MeshSizeFromPoints = 1;
Mesh.MeshSizeFromCurvature = 0;
Mesh.Algorithm = 6;   // Frontal-Delaunay (surfaces)
Mesh.Algorithm3D = 1; // Delaunay
Mesh.ElementOrder = 1;
