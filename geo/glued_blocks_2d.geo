// ----------------------------------------------------------------------------
// glued_blocks_2d.geo -- internodes mesh: two unit blocks sharing a conforming
//                        interface, and their union, in one file (2D)
// ----------------------------------------------------------------------------
//
// Models : the blocks [0,1]x[-1,0] (lower) and [0,1]x[0,1] (upper) meshed
//          together, so the interface y = 0 is conforming. The reader numbers
//          each body on its own, so `lower` and `upper` are two bodies with
//          duplicated interface nodes, while `union` is the single body made of
//          both: tied contact between lower and upper must give the solution of
//          union (tests/contact_accuracy.rs).
//
// Parameters (override with -setnumber name value):
//   level  refinement level; the mesh size is h * 2^-level             [0]
//   h      mesh size at level 0                                          [0.2]
//
// Run :    gmsh -2 glued_blocks_2d.geo -format msh41 -o glued_blocks_2d.msh
//
// Physical groups (P1: 3-node triangles, 2-node segments):
//
//                   upper_top
//              +---------------+
//              |     upper     |            union = lower + upper
//              +-- interface --+  y = 0
//              |     lower     |
//              +---------------+
//                   lower_base
// ----------------------------------------------------------------------------

DefineConstant[ level = {0, Name "Parameters/level"} ];
DefineConstant[ h = {0.2, Name "Parameters/h"} ];
s = h * 2^(-level);

Point(1) = {0, -1, 0, s};
Point(2) = {1, -1, 0, s};
Point(3) = {1, 0, 0, s};
Point(4) = {0, 0, 0, s};
Point(5) = {1, 1, 0, s};
Point(6) = {0, 1, 0, s};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 1};
Line(5) = {3, 5};
Line(6) = {5, 6};
Line(7) = {6, 4};
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
Curve Loop(2) = {5, 6, 7, -3};
Plane Surface(2) = {2};

Physical Surface("lower") = {1};
Physical Surface("upper") = {2};
Physical Surface("union") = {1, 2};
Physical Curve("interface") = {3};
Physical Curve("lower_base") = {1};
Physical Curve("upper_top") = {6};
