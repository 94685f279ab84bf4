// ----------------------------------------------------------------------------
// punch_2d.geo -- internodes mesh: a flat punch, sharp or with rounded
//                 corners, pressed onto a wider block, 2D (plane strain)
// ----------------------------------------------------------------------------
//
// Models : the block [-W, W] x [-H, 0] and the punch [-w, w] x [gap, gap + H_p]
//          (w < W) on the same vertical axis x = 0. The punch's lower corners
//          are sharp (rho = 0) or rounded with radius rho: its face is then the
//          flat segment |x| <= w - rho at y = gap and two quarter circles up to
//          the sides x = +-w at y = gap + rho. The block's top edge is split at
//          x = +-w, so the punch's footprint ends on block nodes. gap = 0: the
//          punch's flat face touches the block top; gap < 0: meshed
//          overlapping. The bodies are disjoint meshes (no shared nodes).
//          Block sizes: h_b within r_c of the footprint (distance from the
//          segment |x| <= w, y = 0), growing linearly to h_far at distance
//          d_far; the punch is meshed uniformly with h_p.
//
// Parameters (override with  -setnumber name value; lengths in model units):
//   level  refinement level (integer, may be negative to coarsen);
//          every mesh size below is multiplied by 2^-level          [0]
//   W      half-width of the block                                   [1]
//   H      height of the block                                       [1]
//   w      half-width of the punch (< W)                             [0.25]
//   H_p    height of the punch                                       [0.25]
//   rho    radius of the punch's lower corners (0: sharp;
//          0 <= rho < min(w, H_p))                                   [0]
//   gap    height of the punch's flat face above y = 0 (neg. =
//          overlap)                                                  [0]
//   h_b    block size within r_c of the footprint (level 0)          [1/40]
//   h_far  block size far from it (level 0)                          [1/4]
//   r_c    distance from the footprint with size h_b                 [w / 2]
//   d_far  distance from the footprint where h_far is reached        [1]
//   h_p    punch size (level 0)                                      [h_b]
//
// Run :    gmsh -2 punch_2d.geo -format msh41 -o punch_2d.msh
//          gmsh -2 punch_2d.geo -setnumber rho 0.05 -setnumber h_p 0.01 -o rounded.msh
//
// Physical groups (P1: 3-node triangles, 2-node lines):
//
//                         punch_top (y = gap + H_p)
//                      +-------------------+
//          punch_sides |       punch       | punch_sides (x = +-w)
//                      \___________________/  <- punch_contact (face + rounded
//                                                corners, y = gap)
//   (-W,0) +-----------o-------------------o-----------+ (W,0)
//          |     block_contact (whole top edge, split at x = +-w)   |
//   block_ |                                                        | block_
//   sides  |                      block                             | sides
//          |                                                        |
//  (-W,-H) +--------------------------------------------------------+ (W,-H)
//                                block_base
//
// Boundary lines are oriented counter-clockwise around their body (the body
// is on the left of each line, outward normal = (dy, -dx)).
// ----------------------------------------------------------------------------

DefineConstant[
  level = {0, Name "Parameters/level"},
  W = {1, Name "Parameters/W"},
  H = {1, Name "Parameters/H"},
  w = {0.25, Name "Parameters/w"},
  H_p = {0.25, Name "Parameters/H_p"},
  rho = {0, Name "Parameters/rho"},
  gap = {0, Name "Parameters/gap"},
  h_b = {1 / 40, Name "Parameters/h_b"},
  h_far = {1 / 4, Name "Parameters/h_far"},
  r_c = {w / 2, Name "Parameters/r_c"},
  d_far = {1, Name "Parameters/d_far"},
  h_p = {h_b, Name "Parameters/h_p"}
];

If (w >= W || rho < 0 || rho >= w || rho >= H_p)
  Error("punch_2d.geo: needs w < W and 0 <= rho < min(w, H_p)");
  Abort;
EndIf

Geometry.AutoCoherence = 0; // never merge coincident points (bodies are disjoint)
s = 2 ^ (-level);           // size factor of this refinement level

// --- block [-W, W] x [-H, 0], top edge split at x = -w and x = w -----------------
p1 = newp; Point(p1) = {-W, -H, 0};
p2 = newp; Point(p2) = {W, -H, 0};
p3 = newp; Point(p3) = {W, 0, 0};
p4 = newp; Point(p4) = {w, 0, 0};
p5 = newp; Point(p5) = {-w, 0, 0};
p6 = newp; Point(p6) = {-W, 0, 0};
l_base = newl; Line(l_base) = {p1, p2};
l_right = newl; Line(l_right) = {p2, p3};
l_top1 = newl; Line(l_top1) = {p3, p4};
l_foot = newl; Line(l_foot) = {p4, p5};   // the footprint |x| <= w
l_top2 = newl; Line(l_top2) = {p5, p6};
l_left = newl; Line(l_left) = {p6, p1};
cl = newll; Curve Loop(cl) = {l_base, l_right, l_top1, l_foot, l_top2, l_left};
s_block = news; Plane Surface(s_block) = {cl};

// --- punch [-w, w] x [gap, gap + H_p], lower corners of radius rho ----------------
yt = gap + H_p;
q_tr = newp; Point(q_tr) = {w, yt, 0};
q_tl = newp; Point(q_tl) = {-w, yt, 0};
If (rho > 0)
  q1 = newp; Point(q1) = {-w + rho, gap, 0};      // flat face, left end
  q2 = newp; Point(q2) = {w - rho, gap, 0};       // flat face, right end
  c2 = newp; Point(c2) = {w - rho, gap + rho, 0}; // centre of the right corner
  q3 = newp; Point(q3) = {w, gap + rho, 0};
  c1 = newp; Point(c1) = {-w + rho, gap + rho, 0};
  q4 = newp; Point(q4) = {-w, gap + rho, 0};
  u_face = newl; Line(u_face) = {q1, q2};
  u_arc2 = newl; Circle(u_arc2) = {q2, c2, q3};
  u_right = newl; Line(u_right) = {q3, q_tr};
  u_top = newl; Line(u_top) = {q_tr, q_tl};
  u_left = newl; Line(u_left) = {q_tl, q4};
  u_arc1 = newl; Circle(u_arc1) = {q4, c1, q1};
  cl = newll; Curve Loop(cl) = {u_face, u_arc2, u_right, u_top, u_left, u_arc1};
  punch_face[] = {u_arc1, u_face, u_arc2};
  punch_points[] = {q_tr, q_tl, q1, q2, q3, q4};
Else
  q1 = newp; Point(q1) = {-w, gap, 0};
  q2 = newp; Point(q2) = {w, gap, 0};
  u_face = newl; Line(u_face) = {q1, q2};
  u_right = newl; Line(u_right) = {q2, q_tr};
  u_top = newl; Line(u_top) = {q_tr, q_tl};
  u_left = newl; Line(u_left) = {q_tl, q1};
  cl = newll; Curve Loop(cl) = {u_face, u_right, u_top, u_left};
  punch_face[] = {u_face};
  punch_points[] = {q_tr, q_tl, q1, q2};
EndIf
s_punch = news; Plane Surface(s_punch) = {cl};

// --- mesh size: the block refined towards the footprint, the punch uniform --------
Field[1] = Distance;
Field[1].CurvesList = {l_foot};
Field[1].NumPointsPerCurve = 200;
Field[2] = Threshold;
Field[2].InField = 1;
Field[2].SizeMin = h_b * s;
Field[2].SizeMax = h_far * s;
Field[2].DistMin = r_c;
Field[2].DistMax = d_far;
Field[3] = Restrict;
Field[3].InField = 2;
Field[3].SurfacesList = {s_block};
Field[3].CurvesList = {l_base, l_right, l_top1, l_foot, l_top2, l_left};
Field[3].PointsList = {p1, p2, p3, p4, p5, p6};
Field[4] = MathEval;
Field[4].F = Sprintf("%.17g", h_p * s);
Field[5] = Restrict;
Field[5].InField = 4;
Field[5].SurfacesList = {s_punch};
Field[5].CurvesList = {punch_face[], u_right, u_top, u_left};
Field[5].PointsList = {punch_points[]};
Field[6] = Min;
Field[6].FieldsList = {3, 5};
Background Field = 6;

Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.Algorithm = 6; // Frontal-Delaunay
Mesh.ElementOrder = 1;

// --- physical groups ------------------------------------------------------------
Physical Surface("punch") = {s_punch};
Physical Surface("block") = {s_block};
Physical Curve("punch_contact") = {punch_face[]};
Physical Curve("punch_top") = {u_top};
Physical Curve("punch_sides") = {u_right, u_left};
Physical Curve("block_contact") = {l_top1, l_foot, l_top2};
Physical Curve("block_base") = {l_base};
Physical Curve("block_sides") = {l_right, l_left};
