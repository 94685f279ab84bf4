// ----------------------------------------------------------------------------
// two_blocks_2d.geo -- internodes mesh: two stacked blocks, 2D (plane strain),
//                      non-matching meshes on a flat interface
// ----------------------------------------------------------------------------
//
// Models : lower body [0,L] x [-H_l,0] and upper body [0,L] x [0,H_u] meeting
//          on the line y = 0. Uniform (unstructured) meshes with a different
//          size per body, so the interface meshes do not match. The bodies
//          are separate geometric entities: no shared points, no shared mesh
//          nodes (the interface corners are duplicated). Used for patch tests
//          (uniform compression / tension, constant interface pressure) and
//          for the interface interpolation tests.
//
// Parameters (override with  -setnumber name value; lengths in model units):
//   level  refinement level (integer, may be negative to coarsen);
//          every mesh size below is multiplied by 2^-level          [0]
//   L      width of both blocks                                      [1]
//   H_l    height of the lower block                                 [1]
//   H_u    height of the upper block                                 [1]
//   h_l    mesh size of the lower block (level 0)                    [1/6]
//   h_u    mesh size of the upper block (level 0)                    [1/5]
//
// Run :    gmsh -2 two_blocks_2d.geo -format msh41 -o two_blocks_2d.msh
//          gmsh -2 two_blocks_2d.geo -setnumber level 1 -o tb2_l1.msh
//
// Physical groups (P1: 3-node triangles, 2-node lines):
//
//                          upper_top (y = H_u)
//           (0,H_u) +---------------------------+ (L,H_u)
//                   |                           |
//      upper_sides  |          upper            |  upper_sides
//                   |                           |
//             (0,0) +---------------------------+ (L,0)  <- upper_contact
//             (0,0) +---------------------------+ (L,0)  <- lower_contact
//                   |                           |
//      lower_sides  |          lower            |  lower_sides
//                   |                           |
//          (0,-H_l) +---------------------------+ (L,-H_l)
//                          lower_base (y = -H_l)
//
// Boundary lines are oriented counter-clockwise around their body (the body
// is on the left of each line, outward normal = (dy, -dx)).
// ----------------------------------------------------------------------------

DefineConstant[
  level = {0, Name "Parameters/level"},
  L = {1, Name "Parameters/L"},
  H_l = {1, Name "Parameters/H_l"},
  H_u = {1, Name "Parameters/H_u"},
  h_l = {1 / 6, Name "Parameters/h_l"},
  h_u = {1 / 5, Name "Parameters/h_u"}
];

Geometry.AutoCoherence = 0; // never merge coincident points (bodies are disjoint)
s = 2 ^ (-level);           // size factor of this refinement level
hl = h_l * s;
hu = h_u * s;

// --- lower block [0,L] x [-H_l,0] ------------------------------------------------
p1 = newp; Point(p1) = {0, -H_l, 0, hl};
p2 = newp; Point(p2) = {L, -H_l, 0, hl};
p3 = newp; Point(p3) = {L, 0, 0, hl};
p4 = newp; Point(p4) = {0, 0, 0, hl};
lo_base = newl; Line(lo_base) = {p1, p2};
lo_right = newl; Line(lo_right) = {p2, p3};
lo_top = newl; Line(lo_top) = {p3, p4};
lo_left = newl; Line(lo_left) = {p4, p1};
cl = newll; Curve Loop(cl) = {lo_base, lo_right, lo_top, lo_left};
s_lower = news; Plane Surface(s_lower) = {cl};

// --- upper block [0,L] x [0,H_u] --------------------------------------------------
q1 = newp; Point(q1) = {0, 0, 0, hu};
q2 = newp; Point(q2) = {L, 0, 0, hu};
q3 = newp; Point(q3) = {L, H_u, 0, hu};
q4 = newp; Point(q4) = {0, H_u, 0, hu};
up_bot = newl; Line(up_bot) = {q1, q2};
up_right = newl; Line(up_right) = {q2, q3};
up_top = newl; Line(up_top) = {q3, q4};
up_left = newl; Line(up_left) = {q4, q1};
cl = newll; Curve Loop(cl) = {up_bot, up_right, up_top, up_left};
s_upper = news; Plane Surface(s_upper) = {cl};

// --- mesh size: uniform per body (from the point sizes) -------------------------
Mesh.MeshSizeFromPoints = 1;
Mesh.MeshSizeFromCurvature = 0;
Mesh.Algorithm = 6; // Frontal-Delaunay
Mesh.ElementOrder = 1;

// --- physical groups ------------------------------------------------------------
Physical Surface("lower") = {s_lower};
Physical Surface("upper") = {s_upper};
Physical Curve("lower_contact") = {lo_top};
Physical Curve("upper_contact") = {up_bot};
Physical Curve("lower_base") = {lo_base};
Physical Curve("upper_top") = {up_top};
Physical Curve("lower_sides") = {lo_right, lo_left};
Physical Curve("upper_sides") = {up_right, up_left};
// Corner points, to pin the blocks against rigid-body motions without lateral rollers:
// the left end of the lower base and of the upper top.
Physical Point("lower_corner") = {p1};
Physical Point("upper_corner") = {q4};
