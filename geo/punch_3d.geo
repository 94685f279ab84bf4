// ----------------------------------------------------------------------------
// punch_3d.geo -- internodes mesh: a flat cylindrical punch, sharp or with a
//                 rounded edge, pressed onto a wider block, 3D
// ----------------------------------------------------------------------------
//
// Models : the block [-W, W]^2 x [-H, 0] and the punch, a cylinder of radius
//          w < W and height H_p on the z axis, its flat face at z = gap. The
//          punch's lower edge is sharp (rho = 0) or rounded with radius rho:
//          its face is then the disc r <= w - rho at z = gap and a fillet (a
//          quarter circle of radius rho in every meridian plane, the surface
//          interpolated between its boundary arcs) up to the cylinder r = w at
//          z = gap + rho. The block's top face holds the circle r = w (the
//          footprint's rim), split into a disc and the rest. With rho = 0 the
//          rim of the punch's face and the block's circle carry the same
//          nodes (transfinite arcs, the finer of the two sizes), so the
//          footprint ends on block nodes that are also punch nodes. gap = 0:
//          the punch's flat face touches the block top; gap < 0: meshed
//          overlapping. The bodies are disjoint meshes (no shared nodes).
//          Block sizes: h_b within r_c of the footprint (distance from its rim
//          circle or from its centre: the whole disc is within w / 2 of one of
//          them), growing linearly to h_far at distance d_far; the punch is
//          meshed uniformly with h_p.
//
// Parameters (override with  -setnumber name value; lengths in model units):
//   level  refinement level (integer, may be negative to coarsen);
//          every mesh size below is multiplied by 2^-level          [0]
//   W      half-width of the block (x and y)                         [1]
//   H      height of the block                                       [1]
//   w      radius of the punch (< W)                                 [0.25]
//   H_p    height of the punch                                       [0.25]
//   rho    radius of the punch's lower edge (0: sharp;
//          0 <= rho < min(w, H_p))                                   [0]
//   gap    height of the punch's flat face above z = 0 (neg. =
//          overlap)                                                  [0]
//   h_b    block size within r_c of the footprint (level 0)          [1/16]
//   h_far  block size far from it (level 0)                          [1/3]
//   r_c    distance from the footprint's rim or centre with size h_b [w / 2]
//   d_far  distance where h_far is reached                           [1]
//   h_p    punch size (level 0)                                      [h_b]
//
// Run :    gmsh -3 punch_3d.geo -format msh41 -o punch_3d.msh
//          gmsh -3 punch_3d.geo -setnumber rho 0.05 -setnumber h_p 0.03 -o rounded.msh
//
// Physical groups (P1: 4-node tetrahedra, 3-node triangles), section y = 0:
//
//                         punch_top (z = gap + H_p)
//                      +-------------------+
//          punch_sides |       punch       | punch_sides (cylinder r = w)
//                      \___________________/  <- punch_contact (face + fillet)
//   (-W,0) +-----------o-------------------o-----------+ (W,0)
//          |   block_contact (whole top face; circle r = w in it)   |
//   block_ |                                                        | block_
//   sides  |                      block                             | sides
//          |                                                        |
//  (-W,-H) +--------------------------------------------------------+ (W,-H)
//                                block_base
//
// Boundary triangles are oriented with their right-hand normal pointing out
// of their body.
// ----------------------------------------------------------------------------

DefineConstant[
  level = {0, Name "Parameters/level"},
  W = {1, Name "Parameters/W"},
  H = {1, Name "Parameters/H"},
  w = {0.25, Name "Parameters/w"},
  H_p = {0.25, Name "Parameters/H_p"},
  rho = {0, Name "Parameters/rho"},
  gap = {0, Name "Parameters/gap"},
  h_b = {1 / 16, Name "Parameters/h_b"},
  h_far = {1 / 3, Name "Parameters/h_far"},
  r_c = {w / 2, Name "Parameters/r_c"},
  d_far = {1, Name "Parameters/d_far"},
  h_p = {h_b, Name "Parameters/h_p"}
];

If (w >= W || rho < 0 || rho >= w || rho >= H_p)
  Error("punch_3d.geo: needs w < W and 0 <= rho < min(w, H_p)");
  Abort;
EndIf

Geometry.AutoCoherence = 0; // never merge coincident points (bodies are disjoint)
s = 2 ^ (-level);           // size factor of this refinement level

// --- block [-W, W]^2 x [-H, 0], the circle r = w in its top face --------------------
b1 = newp; Point(b1) = {-W, -W, -H};
b2 = newp; Point(b2) = {W, -W, -H};
b3 = newp; Point(b3) = {W, W, -H};
b4 = newp; Point(b4) = {-W, W, -H};
t1 = newp; Point(t1) = {-W, -W, 0};
t2 = newp; Point(t2) = {W, -W, 0};
t3 = newp; Point(t3) = {W, W, 0};
t4 = newp; Point(t4) = {-W, W, 0};
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
o = newp; Point(o) = {0, 0, 0};            // centre of the footprint (not a mesh node)
f1 = newp; Point(f1) = {w, 0, 0};
f2 = newp; Point(f2) = {0, w, 0};
f3 = newp; Point(f3) = {-w, 0, 0};
f4 = newp; Point(f4) = {0, -w, 0};
fa1 = newl; Circle(fa1) = {f1, o, f2};
fa2 = newl; Circle(fa2) = {f2, o, f3};
fa3 = newl; Circle(fa3) = {f3, o, f4};
fa4 = newl; Circle(fa4) = {f4, o, f1};
rim[] = {fa1, fa2, fa3, fa4};
// loops counter-clockwise seen from outside (outward right-hand normal)
cl = newll; Curve Loop(cl) = {-lb4, -lb3, -lb2, -lb1};
s_base = news; Plane Surface(s_base) = {cl};
cl_out = newll; Curve Loop(cl_out) = {lt1, lt2, lt3, lt4};
cl_rim = newll; Curve Loop(cl_rim) = {fa1, fa2, fa3, fa4};
s_top_out = news; Plane Surface(s_top_out) = {cl_out, cl_rim};
s_foot = news; Plane Surface(s_foot) = {cl_rim};
cl = newll; Curve Loop(cl) = {lb1, lv2, -lt1, -lv1};
s_sides[0] = news; Plane Surface(s_sides[0]) = {cl};
cl = newll; Curve Loop(cl) = {lb2, lv3, -lt2, -lv2};
s_sides[1] = news; Plane Surface(s_sides[1]) = {cl};
cl = newll; Curve Loop(cl) = {lb3, lv4, -lt3, -lv3};
s_sides[2] = news; Plane Surface(s_sides[2]) = {cl};
cl = newll; Curve Loop(cl) = {lb4, lv1, -lt4, -lv4};
s_sides[3] = news; Plane Surface(s_sides[3]) = {cl};
sl = newsl; Surface Loop(sl) = {s_base, s_top_out, s_foot, s_sides[]};
v_block = newv; Volume(v_block) = {sl};
block_curves[] = {lb1, lb2, lb3, lb4, lt1, lt2, lt3, lt4, lv1, lv2, lv3, lv4, rim[]};
block_points[] = {b1, b2, b3, b4, t1, t2, t3, t4, f1, f2, f3, f4};

// --- punch: cylinder r = w on z in [gap, gap + H_p], lower edge of radius rho ----------
// circles of the punch: ring k at height z_k and radius r_k, points at angles 0, 90, 180, 270
Macro Ring
  rg_c = newp; Point(rg_c) = {0, 0, rg_z};
  rg_p[0] = newp; Point(rg_p[0]) = {rg_r, 0, rg_z};
  rg_p[1] = newp; Point(rg_p[1]) = {0, rg_r, rg_z};
  rg_p[2] = newp; Point(rg_p[2]) = {-rg_r, 0, rg_z};
  rg_p[3] = newp; Point(rg_p[3]) = {0, -rg_r, rg_z};
  For k In {0:3}
    rg_a[k] = newl; Circle(rg_a[k]) = {rg_p[k], rg_c, rg_p[(k + 1) % 4]};
  EndFor
Return

zt = gap + H_p;
rg_z = gap; rg_r = w - rho; Call Ring;          // rim of the flat face
face_p[] = rg_p[]; face_a[] = rg_a[];
rg_z = zt; rg_r = w; Call Ring;                 // top rim
top_p[] = rg_p[]; top_a[] = rg_a[];
cl = newll; Curve Loop(cl) = {-face_a[3], -face_a[2], -face_a[1], -face_a[0]};
s_face = news; Plane Surface(s_face) = {cl};
cl = newll; Curve Loop(cl) = {top_a[]};
s_ptop = news; Plane Surface(s_ptop) = {cl};
If (rho > 0)
  rg_z = gap + rho; rg_r = w; Call Ring;        // where the fillet meets the cylinder
  mid_p[] = rg_p[]; mid_a[] = rg_a[];
  For k In {0:3}
    // meridian quarter circle from the face rim to the cylinder, centre at r = w - rho, z = gap + rho
    mc = newp; Point(mc) = {(w - rho) * Cos(k * Pi / 2), (w - rho) * Sin(k * Pi / 2), gap + rho};
    mer[k] = newl; Circle(mer[k]) = {face_p[k], mc, mid_p[k]};
  EndFor
  For k In {0:3}
    cl = newll; Curve Loop(cl) = {face_a[k], mer[(k + 1) % 4], -mid_a[k], -mer[k]};
    s_fillet[k] = news; Surface(s_fillet[k]) = {cl};
  EndFor
  low_p[] = mid_p[]; low_a[] = mid_a[];
  punch_face[] = {s_face, s_fillet[]};
  punch_curves[] = {mid_a[], mer[]};
  punch_points[] = {mid_p[]};
Else
  low_p[] = face_p[]; low_a[] = face_a[];
  punch_face[] = {s_face};
  punch_curves[] = {};
  punch_points[] = {};
  // the face rim and the block's circle carry the same nodes
  n_arc = Ceil(Pi * w / 2 / (Min(h_b, h_p) * s)) + 1;
  Transfinite Curve{rim[], face_a[]} = n_arc;
EndIf
For k In {0:3}
  vert[k] = newl; Line(vert[k]) = {low_p[k], top_p[k]};
EndFor
For k In {0:3}
  cl = newll; Curve Loop(cl) = {low_a[k], vert[(k + 1) % 4], -top_a[k], -vert[k]};
  s_pside[k] = news; Surface(s_pside[k]) = {cl};
EndFor
punch_curves[] += {face_a[], top_a[], vert[]};
punch_points[] += {face_p[], top_p[]};
sl = newsl; Surface Loop(sl) = {punch_face[], s_pside[], s_ptop};
v_punch = newv; Volume(v_punch) = {sl};

// --- mesh size: the block refined towards the footprint, the punch uniform --------
Field[1] = Distance;
Field[1].PointsList = {o};
Field[1].CurvesList = {rim[]};
Field[1].NumPointsPerCurve = 200;
Field[2] = Threshold;
Field[2].InField = 1;
Field[2].SizeMin = h_b * s;
Field[2].SizeMax = h_far * s;
Field[2].DistMin = r_c;
Field[2].DistMax = d_far;
Field[3] = Restrict;
Field[3].InField = 2;
Field[3].VolumesList = {v_block};
Field[3].SurfacesList = {s_base, s_top_out, s_foot, s_sides[]};
Field[3].CurvesList = {block_curves[]};
Field[3].PointsList = {block_points[]};
Field[4] = MathEval;
Field[4].F = Sprintf("%.17g", h_p * s);
Field[5] = Restrict;
Field[5].InField = 4;
Field[5].VolumesList = {v_punch};
Field[5].SurfacesList = {punch_face[], s_pside[], s_ptop};
Field[5].CurvesList = {punch_curves[]};
Field[5].PointsList = {punch_points[]};
Field[6] = Min;
Field[6].FieldsList = {3, 5};
Background Field = 6;

Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.Algorithm = 6;   // Frontal-Delaunay (surfaces)
Mesh.Algorithm3D = 1; // Delaunay
Mesh.ElementOrder = 1;

// --- physical groups ------------------------------------------------------------
Physical Volume("punch") = {v_punch};
Physical Volume("block") = {v_block};
Physical Surface("punch_contact") = {punch_face[]};
Physical Surface("punch_top") = {s_ptop};
Physical Surface("punch_sides") = {s_pside[]};
Physical Surface("block_contact") = {s_top_out, s_foot};
Physical Surface("block_base") = {s_base};
Physical Surface("block_sides") = {s_sides[]};
