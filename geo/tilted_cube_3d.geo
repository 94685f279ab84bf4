// ----------------------------------------------------------------------------
// tilted_cube_3d.geo -- internodes mesh: a cube tilted so that one edge points
//                       down, that edge pressed onto a block, 3D
//                       (validation/edge_sweep.py)
// ----------------------------------------------------------------------------
//
// Models : the block [-W, W]^2 x [-H, 0] and a cube of side a, turned by theta
//          about the x axis (so that one edge, along x, is its lowest line and
//          the two faces that meet there slope by theta and 90 - theta from
//          the horizontal), then by phi about the vertical axis (the edge not
//          parallel to x or y), its lowest edge at z = gap, its middle at
//          (sx, sy) (off the origin). Both bodies are refined towards the
//          lowest edge: size h_c (cube) and h_b (block) within r_c of that
//          edge, growing linearly to h_far at d_far. The bodies are disjoint
//          meshes (no shared nodes, no boolean operation).
//
// Parameters (override with  -setnumber name value; lengths in model units):
//   level  refinement level (integer, may be negative to coarsen);
//          every mesh size below is multiplied by 2^-level          [0]
//   W      half-width of the block                                   [0.6]
//   H      height of the block                                       [0.5]
//   a      side of the cube                                          [0.4]
//   theta  tilt about x, degrees (0 < theta < 90; 45: symmetric)     [20]
//   phi    turn about the vertical axis, degrees                     [17]
//   sx, sy middle of the lowest edge                                 [0.0031, 0.0057]
//   gap    height of the lowest edge above z = 0 (neg.: overlap)     [0]
//   h_c    cube size near the edge                                   [0.01]
//   h_b    block size near the edge                                  [h_c]
//   r_c    distance from the edge with sizes h_c, h_b                [0.04]
//   h_far  size far from the edge                                    [0.1]
//   d_far  distance where h_far is reached                           [0.3]
//
// Run :    gmsh -3 geo/tilted_cube_3d.geo -format msh41 -o tilted_cube.msh
//
// Physical groups (P1: 4-node tetrahedra, 3-node triangles), section across
// the edge:
//
//                      /\   <- cube_top: the two faces that meet at the top edge
//                     /  \
//                    / cube\      cube_ends: the two faces across the edge's ends
//                    \     /
//                     \   / <- cube_contact: the two faces that meet at the
//   (-W,0) +-----------\/-----------+ (W,0)     lowest edge
//          | block_contact (top)    |
//   block_ |        block           | block_sides
//  (-W,-H) +------------------------+ (W,-H)
//                 block_base
//
// OpenCASCADE kernel (rotations of a box), unlike the other scripts of geo/;
// the solver and the references orient boundary facets from their cells.
// ----------------------------------------------------------------------------

SetFactory("OpenCASCADE");
DefineConstant[
  level = {0, Name "Parameters/level"},
  W = {0.6, Name "Parameters/W"},
  H = {0.5, Name "Parameters/H"},
  a = {0.4, Name "Parameters/a"},
  theta = {20, Name "Parameters/theta"},
  phi = {17, Name "Parameters/phi"},
  sx = {0.0031, Name "Parameters/sx"},
  sy = {0.0057, Name "Parameters/sy"},
  gap = {0, Name "Parameters/gap"},
  h_c = {0.01, Name "Parameters/h_c"},
  h_b = {h_c, Name "Parameters/h_b"},
  r_c = {0.04, Name "Parameters/r_c"},
  h_far = {0.1, Name "Parameters/h_far"},
  d_far = {0.3, Name "Parameters/d_far"}
];
If (theta <= 0 || theta >= 90 || a * Sqrt(2) + Fabs(sx) + Fabs(sy) >= 2 * W)
  Error("tilted_cube_3d.geo: needs 0 < theta < 90 and the cube over the block");
  Abort;
EndIf
Geometry.AutoCoherence = 0;
sf = 2 ^ (-level);  // size factor of this refinement level
t = theta * Pi / 180;
f = phi * Pi / 180;

Box(1) = {-W, -W, -H, 2 * W, 2 * W, H};
Box(2) = {-a / 2, -a / 2, -a / 2, a, a, a};
Rotate {{1, 0, 0}, {0, 0, 0}, t} { Volume{2}; }
Rotate {{0, 0, 1}, {0, 0, 0}, f} { Volume{2}; }
// the lowest edge's middle, (0, -a/2, -a/2) turned, to (sx, sy, gap)
y_e = -a / 2 * (Cos(t) - Sin(t));
Translate {sx + Sin(f) * y_e, sy - Cos(f) * y_e, gap + a / 2 * (Sin(t) + Cos(t))} { Volume{2}; }
eps = 1e-6;
edge[] = Curve In BoundingBox{-W + eps, -W + eps, gap - eps, W - eps, W - eps, gap + eps};
If (#edge[] != 1)
  Error("tilted_cube_3d.geo: found %g lowest edges, not 1", #edge[]);
  Abort;
EndIf

// OpenCASCADE numbers a box's faces x-, x+, y-, y+, z-, z+: the cube's are 7 to 12; the
// lowest edge is where y- (9) and z- (11) meet, the top edge where y+ (10) and z+ (12) meet.
Physical Volume("block") = {1};
Physical Volume("cube") = {2};
Physical Surface("block_contact") = {6};
Physical Surface("block_base") = {5};
Physical Surface("block_sides") = {1, 2, 3, 4};
Physical Surface("cube_contact") = {9, 11};
Physical Surface("cube_top") = {10, 12};
Physical Surface("cube_ends") = {7, 8};

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

Field[1] = Distance;
Field[1].CurvesList = {edge[0]};
Field[1].NumPointsPerCurve = 400;
Field[2] = Threshold;
Field[2].InField = 1;
Field[2].SizeMin = h_c * sf;
Field[2].SizeMax = h_far * sf;
Field[2].DistMin = r_c;
Field[2].DistMax = d_far;
cl_s[] = {7, 8, 9, 10, 11, 12};
Call Closure;
Field[3] = Restrict;
Field[3].InField = 2;
Field[3].VolumesList = {2};
Field[3].SurfacesList = {cl_s[]};
Field[3].CurvesList = {cl_c[]};
Field[3].PointsList = {cl_p[]};
Field[5] = Threshold;
Field[5].InField = 1;
Field[5].SizeMin = h_b * sf;
Field[5].SizeMax = h_far * sf;
Field[5].DistMin = r_c;
Field[5].DistMax = d_far;
cl_s[] = {1, 2, 3, 4, 5, 6};
Call Closure;
Field[6] = Restrict;
Field[6].InField = 5;
Field[6].VolumesList = {1};
Field[6].SurfacesList = {cl_s[]};
Field[6].CurvesList = {cl_c[]};
Field[6].PointsList = {cl_p[]};
Field[7] = Min;
Field[7].FieldsList = {3, 6};
Background Field = 7;

Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.Algorithm = 6;
Mesh.Algorithm3D = 1;
Mesh.ElementOrder = 1;
