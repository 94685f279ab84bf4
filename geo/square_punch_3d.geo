// ----------------------------------------------------------------------------
// square_punch_3d.geo -- internodes mesh: a square flat punch, its edges sharp or
//                        filleted, pressed onto a wider block, its footprint off
//                        the block's mesh lines, 3D (validation/edge_sweep.py)
// ----------------------------------------------------------------------------
//
// Models : the block [-W, W]^2 x [-H, 0] and the punch, the box
//          [sx - w, sx + w] x [sy - w, sy + w] x [gap, gap + H_p]. With rho > 0
//          the punch's four lower edges and its four vertical edges are
//          filleted with radius rho (OpenCASCADE fillets): its lower surface is
//          then exactly the lower surface of the square of half-width w - rho,
//          grown by a ball of radius rho (flat face, quarter cylinders along the
//          edges, sphere octants at the corners). The shift (sx, sy) puts the
//          punch's edges off the block's mesh lines; the block's top face is one
//          surface, not split under the punch, so no block node is placed on the
//          footprint's rim on purpose. The bodies are disjoint meshes (no shared
//          nodes, no boolean operation). Sizes: the block h_b within the box
//          |x|, |y| <= w + d_c, z >= -d_c around the footprint, growing over
//          the distance d_c to h_far; the punch h_p everywhere, its fillets
//          h_fillet (default min(h_p, rho / 4): the exact fillet is the
//          reference's, the P1 chord's sag h_fillet^2 / (8 rho) stays below
//          rho / 128).
//
// Parameters (override with  -setnumber name value; lengths in model units):
//   level  refinement level (integer, may be negative to coarsen);
//          every mesh size below is multiplied by 2^-level          [0]
//   W      half-width of the block                                   [1]
//   H      height of the block                                       [1]
//   w      half-width of the punch (< W)                             [0.3]
//   H_p    height of the punch                                       [0.5]
//   rho    fillet radius (0: sharp edges; 0 <= rho < w / 2)          [0]
//   sx, sy shift of the punch's axis off the origin                  [0.0137, 0.0071]
//   gap    height of the punch's face above z = 0 (neg.: overlap)    [0]
//   h_b    block size around the footprint                           [0.05]
//   h_far  block size far from it                                    [0.25]
//   d_c    margin of the refined box around the footprint            [0.15]
//   h_p    punch size                                                [h_b]
//   h_fillet  punch size on the fillets                              [min(h_p, rho / 4)]
//
// Run :    gmsh -3 geo/square_punch_3d.geo -format msh41 -o square_punch.msh
//          gmsh -3 geo/square_punch_3d.geo -setnumber rho 0.1 -setnumber h_p 0.035 -o filleted.msh
//
// Physical groups (P1: 4-node tetrahedra, 3-node triangles), section y = sy:
//
//                          punch_top (z = gap + H_p)
//                       +-----------------+
//           punch_sides |      punch      | punch_sides
//                       +-----------------+  <- punch_contact (face; with rho > 0
//   (-W,0) +-----------------------------------------+ (W,0)   also the fillets)
//          |     block_contact (the whole top face)  |
//   block_ |                 block                   | block_sides
//   sides  |                                         |
//  (-W,-H) +-----------------------------------------+ (W,-H)
//                           block_base
//
// OpenCASCADE kernel (fillets), unlike the other scripts of geo/; the solver and
// the references orient boundary facets from their cells.
// ----------------------------------------------------------------------------

SetFactory("OpenCASCADE");
DefineConstant[
  level = {0, Name "Parameters/level"},
  W = {1, Name "Parameters/W"},
  H = {1, Name "Parameters/H"},
  w = {0.3, Name "Parameters/w"},
  H_p = {0.5, Name "Parameters/H_p"},
  rho = {0, Name "Parameters/rho"},
  sx = {0.0137, Name "Parameters/sx"},
  sy = {0.0071, Name "Parameters/sy"},
  gap = {0, Name "Parameters/gap"},
  h_b = {0.05, Name "Parameters/h_b"},
  h_far = {0.25, Name "Parameters/h_far"},
  d_c = {0.15, Name "Parameters/d_c"},
  h_p = {h_b, Name "Parameters/h_p"},
  h_fillet = {(rho > 0 && rho / 4 < h_p) ? rho / 4 : h_p, Name "Parameters/h_fillet"}
];
If (w + Fabs(sx) >= W || w + Fabs(sy) >= W || rho < 0 || rho >= w / 2 || rho >= H_p)
  Error("square_punch_3d.geo: needs the punch inside the block and 0 <= rho < min(w / 2, H_p)");
  Abort;
EndIf
Geometry.AutoCoherence = 0;
sf = 2 ^ (-level);  // size factor of this refinement level

Box(1) = {-W, -W, -H, 2 * W, 2 * W, H};
Box(2) = {sx - w, sy - w, gap, 2 * w, 2 * w, H_p};
eps = 1e-6;
If (rho > 0)
  // the four lower edges (in the plane z = gap) and the four vertical edges
  low[] = Curve In BoundingBox{sx - w - eps, sy - w - eps, gap - eps, sx + w + eps, sy + w + eps, gap + eps};
  vertical[] = {};
  For k In {0:3}
    cx = sx + w * (2 * (k % 2) - 1);
    cy = sy + w * (2 * Floor(k / 2) - 1);
    vertical[] += Curve In BoundingBox{cx - eps, cy - eps, gap - eps, cx + eps, cy + eps, gap + H_p + eps};
  EndFor
  punch[] = Fillet{2}{low[], vertical[]}{rho};
Else
  punch[] = {2};
EndIf

// the punch's lower surface: every face of the punch within z <= gap + rho
p_contact[] = Surface In BoundingBox{sx - w - eps, sy - w - eps, gap - eps, sx + w + eps, sy + w + eps, gap + rho + eps};
p_flat[] = Surface In BoundingBox{sx - w - eps, sy - w - eps, gap - eps, sx + w + eps, sy + w + eps, gap + eps};
p_fillet[] = {};
For k In {0:#p_contact[] - 1}
  If (p_contact[k] != p_flat[0])
    p_fillet[] += {p_contact[k]};
  EndIf
EndFor
p_top[] = Surface In BoundingBox{sx - w - eps, sy - w - eps, gap + H_p - eps, sx + w + eps, sy + w + eps, gap + H_p + eps};
p_all[] = Boundary{ Volume{punch[0]}; };
p_sides[] = {};
For k In {0:#p_all[] - 1}
  t = Abs(p_all[k]);
  keep = 1;
  For j In {0:#p_contact[] - 1}
    If (t == p_contact[j])
      keep = 0;
    EndIf
  EndFor
  For j In {0:#p_top[] - 1}
    If (t == p_top[j])
      keep = 0;
    EndIf
  EndFor
  If (keep)
    p_sides[] += {t};
  EndIf
EndFor
// OpenCASCADE numbers a box's faces x-, x+, y-, y+, z-, z+
Physical Volume("block") = {1};
Physical Volume("punch") = {punch[0]};
Physical Surface("block_contact") = {6};
Physical Surface("block_base") = {5};
Physical Surface("block_sides") = {1, 2, 3, 4};
Physical Surface("punch_contact") = {p_contact[]};
Physical Surface("punch_top") = {p_top[]};
Physical Surface("punch_sides") = {p_sides[]};

// the entities of each body (a Restrict field acts on the entities it lists only)
// Closure: cl_s[] (surfaces) -> cl_c[] (their curves, unsigned), cl_p[] (their points)
Macro Closure
  cl_c[] = {};
  For i In {0:#cl_s[] - 1}
    tmp[] = Boundary{ Surface{Abs(cl_s[i])}; };
    For j In {0:#tmp[] - 1}
      cl_c[] += {Abs(tmp[j])};
    EndFor
  EndFor
  cl_p[] = PointsOf{ Surface{cl_s[]}; };
Return
b_surfaces[] = {1, 2, 3, 4, 5, 6};
cl_s[] = b_surfaces[];
Call Closure;
b_curves[] = cl_c[];
b_points[] = cl_p[];
For k In {0:#p_all[] - 1}
  p_all[k] = Abs(p_all[k]);
EndFor
cl_s[] = p_all[];
Call Closure;
pc_curves[] = cl_c[];
pc_points[] = cl_p[];
pf_curves[] = {}; pf_points[] = {};
If (#p_fillet[] > 0)
  cl_s[] = p_fillet[];
  Call Closure;
  pf_curves[] = cl_c[];
  pf_points[] = cl_p[];
EndIf

// sizes: the block refined in a box around the footprint, the punch uniform, finer on the fillets
Field[1] = Box;
Field[1].VIn = h_b * sf;
Field[1].VOut = h_far * sf;
Field[1].XMin = -w - d_c + sx;
Field[1].XMax = w + d_c + sx;
Field[1].YMin = -w - d_c + sy;
Field[1].YMax = w + d_c + sy;
Field[1].ZMin = -d_c;
Field[1].ZMax = eps;
Field[1].Thickness = d_c;
Field[2] = Restrict;
Field[2].InField = 1;
Field[2].VolumesList = {1};
Field[2].SurfacesList = {b_surfaces[]};
Field[2].CurvesList = {b_curves[]};
Field[2].PointsList = {b_points[]};
Field[3] = MathEval;
Field[3].F = Sprintf("%.17g", h_p * sf);
Field[4] = Restrict;
Field[4].InField = 3;
Field[4].VolumesList = {punch[0]};
Field[4].SurfacesList = {p_all[]};
Field[4].CurvesList = {pc_curves[]};
Field[4].PointsList = {pc_points[]};
Field[5] = MathEval;
Field[5].F = Sprintf("%.17g", h_fillet * sf);
Field[6] = Restrict;
Field[6].InField = 5;
Field[6].SurfacesList = {p_fillet[]};
Field[6].CurvesList = {pf_curves[]};
Field[6].PointsList = {pf_points[]};
Field[7] = Min;
If (#p_fillet[] > 0)
  Field[7].FieldsList = {2, 4, 6};
Else
  Field[7].FieldsList = {2, 4};
EndIf
Background Field = 7;

Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.Algorithm = 6;
Mesh.Algorithm3D = 1;
Mesh.ElementOrder = 1;
