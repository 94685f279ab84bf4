// ----------------------------------------------------------------------------
// tilted_square_2d.geo -- internodes mesh: a square turned so that one corner
//                         points down, that corner pressed onto a block, plane
//                         strain (validation/edge_sweep.py)
// ----------------------------------------------------------------------------
//
// Models : the block [-W, W] x [-H, 0] and a square of side a, turned by theta
//          (counter-clockwise) about its centre, so that one corner is its
//          lowest point and the two sides that meet there slope by theta and
//          90 - theta from the horizontal; that corner at (sx, gap) (off the
//          origin). Both bodies are refined towards the corner: size h_c
//          (square) and h_b (block) within r_c of it, growing linearly to
//          h_far at d_far. The bodies are disjoint meshes (no shared nodes, no
//          boolean operation).
//
// Parameters (override with  -setnumber name value; lengths in model units):
//   level  refinement level (integer, may be negative to coarsen);
//          every mesh size below is multiplied by 2^-level          [0]
//   W      half-width of the block                                   [0.6]
//   H      height of the block                                       [0.5]
//   a      side of the square                                        [0.4]
//   theta  turn, degrees (0 < theta < 90; 45: symmetric)             [30]
//   sx     abscissa of the lowest corner                             [0.0013]
//   gap    height of the corner above y = 0 (neg.: overlap)          [0]
//   h_c    square size near the corner                               [0.001]
//   h_b    block size near the corner                                [h_c]
//   r_c    distance from the corner with sizes h_c, h_b              [0.05]
//   h_far  size far from the corner                                  [0.05]
//   d_far  distance where h_far is reached                           [0.3]
//
// Run :    gmsh -2 geo/tilted_square_2d.geo -format msh41 -o tilted_square.msh
//
// Physical groups (P1: 3-node triangles, 2-node lines):
//
//                        /\   <- square_top: the two sides that meet at the top corner
//                       /  \
//                      /    \
//                      \ sq /
//                       \  /  <- square_contact: the two sides that meet at the
//   (-W,0) +-------------\/-------------+ (W,0)   lowest corner
//          | block_contact (top side)   |
//   block_ |           block            | block_sides
//  (-W,-H) +----------------------------+ (W,-H)
//                   block_base
//
// OpenCASCADE kernel (a rotated rectangle), unlike the other scripts of geo/;
// the solver and the references orient boundary facets from their cells.
// ----------------------------------------------------------------------------

SetFactory("OpenCASCADE");
DefineConstant[
  level = {0, Name "Parameters/level"},
  W = {0.6, Name "Parameters/W"},
  H = {0.5, Name "Parameters/H"},
  a = {0.4, Name "Parameters/a"},
  theta = {30, Name "Parameters/theta"},
  sx = {0.0013, Name "Parameters/sx"},
  gap = {0, Name "Parameters/gap"},
  h_c = {0.001, Name "Parameters/h_c"},
  h_b = {h_c, Name "Parameters/h_b"},
  r_c = {0.05, Name "Parameters/r_c"},
  h_far = {0.05, Name "Parameters/h_far"},
  d_far = {0.3, Name "Parameters/d_far"}
];
If (theta <= 0 || theta >= 90 || a * Sqrt(2) + Fabs(sx) >= 2 * W)
  Error("tilted_square_2d.geo: needs 0 < theta < 90 and the square over the block");
  Abort;
EndIf
Geometry.AutoCoherence = 0;
sf = 2 ^ (-level);  // size factor of this refinement level
t = theta * Pi / 180;

Rectangle(1) = {-W, -H, 0, 2 * W, H};
Rectangle(2) = {-a / 2, -a / 2, 0, a, a};
Rotate {{0, 0, 1}, {0, 0, 0}, t} { Surface{2}; }
// the lowest corner, (-a/2, -a/2) turned, to (sx, gap)
Translate {sx + a / 2 * (Cos(t) - Sin(t)), gap + a / 2 * (Sin(t) + Cos(t)), 0} { Surface{2}; }
eps = 1e-9;
corner[] = Point In BoundingBox{sx - eps, gap - eps, -1, sx + eps, gap + eps, 1};
If (#corner[] != 1)
  Error("tilted_square_2d.geo: found %g lowest corners, not 1", #corner[]);
  Abort;
EndIf

// OpenCASCADE numbers a rectangle's sides bottom, right, top, left: the square's are 5 to 8;
// the lowest corner is where the bottom (5) and the left (8) sides meet.
Physical Surface("block") = {1};
Physical Surface("square") = {2};
Physical Curve("block_contact") = {3};
Physical Curve("block_base") = {1};
Physical Curve("block_sides") = {2, 4};
Physical Curve("square_contact") = {5, 8};
Physical Curve("square_top") = {6, 7};

Field[1] = Distance;
Field[1].PointsList = {corner[0]};
Field[2] = Threshold;
Field[2].InField = 1;
Field[2].SizeMin = h_c * sf;
Field[2].SizeMax = h_far * sf;
Field[2].DistMin = r_c;
Field[2].DistMax = d_far;
Field[3] = Restrict;
Field[3].InField = 2;
Field[3].SurfacesList = {2};
Field[3].CurvesList = {5, 6, 7, 8};
Field[3].PointsList = {PointsOf{ Surface{2}; }};
Field[5] = Threshold;
Field[5].InField = 1;
Field[5].SizeMin = h_b * sf;
Field[5].SizeMax = h_far * sf;
Field[5].DistMin = r_c;
Field[5].DistMax = d_far;
Field[6] = Restrict;
Field[6].InField = 5;
Field[6].SurfacesList = {1};
Field[6].CurvesList = {1, 2, 3, 4};
Field[6].PointsList = {PointsOf{ Surface{1}; }};
Field[7] = Min;
Field[7].FieldsList = {3, 6};
Background Field = 7;

Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.Algorithm = 6;
Mesh.ElementOrder = 1;
