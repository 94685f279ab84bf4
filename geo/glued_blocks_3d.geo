// ----------------------------------------------------------------------------
// glued_blocks_3d.geo -- internodes mesh: two unit cubes sharing a conforming
//                        interface, and their union, in one file (3D)
// ----------------------------------------------------------------------------
//
// Models : the cubes [0,1]^2x[-1,0] (lower) and [0,1]^2x[0,1] (upper) meshed
//          together, so the interface z = 0 is conforming; as in
//          glued_blocks_2d.geo, `lower` and `upper` are two bodies with
//          duplicated interface nodes and `union` is the single body of both.
//
// Parameters (override with -setnumber name value):
//   level  refinement level; the mesh size is h * 2^-level             [0]
//   h      mesh size at level 0                                          [0.34]
//
// Run :    gmsh -3 glued_blocks_3d.geo -format msh41 -o glued_blocks_3d.msh
//
// Physical groups (P1: 4-node tetrahedra, 3-node triangles):
//   volumes  lower, upper, union (= lower + upper)
//   surfaces interface (z = 0), lower_base (z = -1), upper_top (z = 1)
// ----------------------------------------------------------------------------

SetFactory("OpenCASCADE");
DefineConstant[ level = {0, Name "Parameters/level"} ];
DefineConstant[ h = {0.34, Name "Parameters/h"} ];
s = h * 2^(-level);

Box(1) = {0, 0, -1, 1, 1, 1};
Box(2) = {0, 0, 0, 1, 1, 1};
v() = BooleanFragments{ Volume{1, 2}; Delete; }{};
Mesh.CharacteristicLengthMin = s;
Mesh.CharacteristicLengthMax = s;

e = 1e-6;
lower() = Volume In BoundingBox{-e, -e, -1 - e, 1 + e, 1 + e, e};
upper() = Volume In BoundingBox{-e, -e, -e, 1 + e, 1 + e, 1 + e};
Physical Volume("lower") = {lower()};
Physical Volume("upper") = {upper()};
Physical Volume("union") = {lower(), upper()};
Physical Surface("interface") = Surface In BoundingBox{-e, -e, -e, 1 + e, 1 + e, e};
Physical Surface("lower_base") = Surface In BoundingBox{-e, -e, -1 - e, 1 + e, 1 + e, -1 + e};
Physical Surface("upper_top") = Surface In BoundingBox{-e, -e, 1 - e, 1 + e, 1 + e, 1 + e};
