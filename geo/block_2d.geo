// ----------------------------------------------------------------------------
// block_2d.geo -- internodes mesh: single elastic block, 2D (plane strain)
// ----------------------------------------------------------------------------
//
// Models : the flat block of half_disc_on_block.geo alone, with the same mesh
//          refinement towards the origin on its top edge. Used to validate
//          single-body solves: a Hertzian pressure p(x) = p0 sqrt(1 - x^2/a^2)
//          is applied on block_top, block_base is clamped.
//
// Geometry (xy plane, y up, lengths in model units, default R = 1):
//          block = [-W, W] x [-H, 0]; the top edge y = 0 contains the origin,
//          which is a mesh node (the top edge is split there).
//
// Parameters (override with  -setnumber name value):
//   level  refinement level (integer, may be negative to coarsen);
//          every mesh size below is multiplied by 2^-level          [0]
//   R      reference radius (size of the indenter of the contact
//          problems; only used for the defaults below)               [1]
//   W      half-width of the block                                   [2 R]
//   H      height of the block                                       [2 R]
//   h_c    mesh size in the contact zone |x| < r_c (level 0)          [R/40]
//   h_far  mesh size far from the origin (level 0)                   [R/2]
//   r_c    radius of the uniformly refined contact zone              [R/4]
//   d_far  distance from the origin where h_far is reached; the
//          size grows linearly from h_c at r_c to h_far at d_far     [2 R]
//
// Run :    gmsh -2 block_2d.geo -format msh41 -o block_2d.msh
//          gmsh -2 block_2d.geo -setnumber level 1 -format msh41 -o l1.msh
//
// Physical groups (P1: 3-node triangles, 2-node lines):
//
//                  block_top (y = 0, whole top edge)
//     (-W,0) +---------------o---------------+ (W,0)
//            |             origin            |
//  block_    |                               |  block_
//  sides     |            block              |  sides
//            |         (surface)             |
//    (-W,-H) +-------------------------------+ (W,-H)
//                        block_base
//
// Boundary lines are oriented counter-clockwise around the block (the body is
// on the left of each line, outward normal = (dy, -dx)).
// ----------------------------------------------------------------------------

DefineConstant[
  level = {0, Name "Parameters/level"},
  R = {1, Name "Parameters/R"},
  W = {2 * R, Name "Parameters/W"},
  H = {2 * R, Name "Parameters/H"},
  h_c = {R / 40, Name "Parameters/h_c"},
  h_far = {R / 2, Name "Parameters/h_far"},
  r_c = {R / 4, Name "Parameters/r_c"},
  d_far = {2 * R, Name "Parameters/d_far"}
];

Geometry.AutoCoherence = 0; // never merge coincident points
s = 2 ^ (-level);           // size factor of this refinement level

// --- block [-W, W] x [-H, 0] -------------------------------------------------
p0 = newp; Point(p0) = {0, 0, 0};
p1 = newp; Point(p1) = {-W, -H, 0};
p2 = newp; Point(p2) = {W, -H, 0};
p3 = newp; Point(p3) = {W, 0, 0};
p4 = newp; Point(p4) = {-W, 0, 0};

l_base = newl; Line(l_base) = {p1, p2};
l_right = newl; Line(l_right) = {p2, p3};
l_top1 = newl; Line(l_top1) = {p3, p0};
l_top2 = newl; Line(l_top2) = {p0, p4};
l_left = newl; Line(l_left) = {p4, p1};
cl = newll; Curve Loop(cl) = {l_base, l_right, l_top1, l_top2, l_left};
s_block = news; Plane Surface(s_block) = {cl};

// --- mesh size: refinement towards the origin ---------------------------------
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
Mesh.Algorithm = 6; // Frontal-Delaunay
Mesh.ElementOrder = 1;

// --- physical groups ------------------------------------------------------------
Physical Surface("block") = {s_block};
Physical Curve("block_top") = {l_top1, l_top2};
Physical Curve("block_base") = {l_base};
Physical Curve("block_sides") = {l_right, l_left};
