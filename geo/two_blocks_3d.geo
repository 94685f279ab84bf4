// ----------------------------------------------------------------------------
// two_blocks_3d.geo -- internodes mesh: two stacked blocks, 3D,
//                      non-matching meshes on a flat interface
// ----------------------------------------------------------------------------
//
// Models : lower body [0,L]^2 x [-H_l,0] and upper body [0,L]^2 x [0,H_u]
//          meeting on the plane z = 0. Uniform (unstructured) meshes with a
//          different size per body, so the interface meshes do not match. The
//          bodies are separate geometric entities: no shared points, no shared
//          mesh nodes (the interface corners and edges are duplicated). Used
//          for patch tests and for the interface interpolation tests.
//
// Parameters (override with  -setnumber name value; lengths in model units):
//   level  refinement level (integer, may be negative to coarsen);
//          every mesh size below is multiplied by 2^-level          [0]
//   L      width of both blocks (x and y)                            [1]
//   H_l    height of the lower block                                 [1]
//   H_u    height of the upper block                                 [1]
//   h_l    mesh size of the lower block (level 0)                    [1/4]
//   h_u    mesh size of the upper block (level 0)                    [1/3]
//
// Run :    gmsh -3 two_blocks_3d.geo -format msh41 -o two_blocks_3d.msh
//          gmsh -3 two_blocks_3d.geo -setnumber level 1 -o tb3_l1.msh
//
// Physical groups (P1: 4-node tetrahedra, 3-node triangles), section y = 0:
//
//                          upper_top (z = H_u)
//           (0,H_u) +---------------------------+ (L,H_u)
//                   |                           |
//      upper_sides  |       upper (volume)      |  upper_sides
//   (x = 0, x = L,  |                           |  (4 lateral faces)
//    y = 0, y = L)  |                           |
//             (0,0) +---------------------------+ (L,0)  <- upper_contact
//             (0,0) +---------------------------+ (L,0)  <- lower_contact
//                   |                           |
//      lower_sides  |       lower (volume)      |  lower_sides
//                   |                           |
//          (0,-H_l) +---------------------------+ (L,-H_l)
//                          lower_base (z = -H_l)
//
// Boundary triangles are oriented with their right-hand normal pointing out
// of their body.
// ----------------------------------------------------------------------------

DefineConstant[
  level = {0, Name "Parameters/level"},
  L = {1, Name "Parameters/L"},
  H_l = {1, Name "Parameters/H_l"},
  H_u = {1, Name "Parameters/H_u"},
  h_l = {1 / 4, Name "Parameters/h_l"},
  h_u = {1 / 3, Name "Parameters/h_u"}
];

Geometry.AutoCoherence = 0; // never merge coincident points (bodies are disjoint)
s = 2 ^ (-level);           // size factor of this refinement level

// --- block macro ---------------------------------------------------------------
// input : bx_x0, bx_x1, bx_y0, bx_y1, bx_z0, bx_z1 (extent), bx_h (mesh size)
// output: bx_vol, bx_bottom, bx_top, bx_sides[]
Macro MakeBlock
  bx_b1 = newp; Point(bx_b1) = {bx_x0, bx_y0, bx_z0, bx_h};
  bx_b2 = newp; Point(bx_b2) = {bx_x1, bx_y0, bx_z0, bx_h};
  bx_b3 = newp; Point(bx_b3) = {bx_x1, bx_y1, bx_z0, bx_h};
  bx_b4 = newp; Point(bx_b4) = {bx_x0, bx_y1, bx_z0, bx_h};
  bx_t1 = newp; Point(bx_t1) = {bx_x0, bx_y0, bx_z1, bx_h};
  bx_t2 = newp; Point(bx_t2) = {bx_x1, bx_y0, bx_z1, bx_h};
  bx_t3 = newp; Point(bx_t3) = {bx_x1, bx_y1, bx_z1, bx_h};
  bx_t4 = newp; Point(bx_t4) = {bx_x0, bx_y1, bx_z1, bx_h};
  bx_lb1 = newl; Line(bx_lb1) = {bx_b1, bx_b2};
  bx_lb2 = newl; Line(bx_lb2) = {bx_b2, bx_b3};
  bx_lb3 = newl; Line(bx_lb3) = {bx_b3, bx_b4};
  bx_lb4 = newl; Line(bx_lb4) = {bx_b4, bx_b1};
  bx_lt1 = newl; Line(bx_lt1) = {bx_t1, bx_t2};
  bx_lt2 = newl; Line(bx_lt2) = {bx_t2, bx_t3};
  bx_lt3 = newl; Line(bx_lt3) = {bx_t3, bx_t4};
  bx_lt4 = newl; Line(bx_lt4) = {bx_t4, bx_t1};
  bx_lv1 = newl; Line(bx_lv1) = {bx_b1, bx_t1};
  bx_lv2 = newl; Line(bx_lv2) = {bx_b2, bx_t2};
  bx_lv3 = newl; Line(bx_lv3) = {bx_b3, bx_t3};
  bx_lv4 = newl; Line(bx_lv4) = {bx_b4, bx_t4};
  // loops are counter-clockwise seen from outside (outward right-hand normal)
  bx_cl = newll; Curve Loop(bx_cl) = {-bx_lb4, -bx_lb3, -bx_lb2, -bx_lb1};
  bx_bottom = news; Plane Surface(bx_bottom) = {bx_cl};
  bx_cl = newll; Curve Loop(bx_cl) = {bx_lt1, bx_lt2, bx_lt3, bx_lt4};
  bx_top = news; Plane Surface(bx_top) = {bx_cl};
  bx_cl = newll; Curve Loop(bx_cl) = {bx_lb1, bx_lv2, -bx_lt1, -bx_lv1};
  bx_sides[0] = news; Plane Surface(bx_sides[0]) = {bx_cl};
  bx_cl = newll; Curve Loop(bx_cl) = {bx_lb2, bx_lv3, -bx_lt2, -bx_lv2};
  bx_sides[1] = news; Plane Surface(bx_sides[1]) = {bx_cl};
  bx_cl = newll; Curve Loop(bx_cl) = {bx_lb3, bx_lv4, -bx_lt3, -bx_lv3};
  bx_sides[2] = news; Plane Surface(bx_sides[2]) = {bx_cl};
  bx_cl = newll; Curve Loop(bx_cl) = {bx_lb4, bx_lv1, -bx_lt4, -bx_lv4};
  bx_sides[3] = news; Plane Surface(bx_sides[3]) = {bx_cl};
  bx_sl = newsl; Surface Loop(bx_sl) = {bx_bottom, bx_top, bx_sides[]};
  bx_vol = newv; Volume(bx_vol) = {bx_sl};
Return

// --- lower block [0,L]^2 x [-H_l,0] ------------------------------------------------
bx_x0 = 0; bx_x1 = L; bx_y0 = 0; bx_y1 = L; bx_z0 = -H_l; bx_z1 = 0; bx_h = h_l * s;
Call MakeBlock;
lo_vol = bx_vol; lo_base = bx_bottom; lo_contact = bx_top; lo_sides[] = bx_sides[];
lo_corner_a = bx_b1; lo_corner_b = bx_b2;

// --- upper block [0,L]^2 x [0,H_u] --------------------------------------------------
bx_x0 = 0; bx_x1 = L; bx_y0 = 0; bx_y1 = L; bx_z0 = 0; bx_z1 = H_u; bx_h = h_u * s;
Call MakeBlock;
up_vol = bx_vol; up_contact = bx_bottom; up_top = bx_top; up_sides[] = bx_sides[];
up_corner_a = bx_t1; up_corner_b = bx_t2;

// --- mesh size: uniform per body (from the point sizes) -------------------------
Mesh.MeshSizeFromPoints = 1;
Mesh.MeshSizeFromCurvature = 0;
Mesh.Algorithm = 6;   // Frontal-Delaunay (surfaces)
Mesh.Algorithm3D = 1; // Delaunay
Mesh.ElementOrder = 1;

// --- physical groups ------------------------------------------------------------
Physical Volume("lower") = {lo_vol};
Physical Volume("upper") = {up_vol};
Physical Surface("lower_contact") = {lo_contact};
Physical Surface("upper_contact") = {up_contact};
Physical Surface("lower_base") = {lo_base};
Physical Surface("upper_top") = {up_top};
Physical Surface("lower_sides") = {lo_sides[]};
Physical Surface("upper_sides") = {up_sides[]};
// Corner points, to pin the blocks against rigid-body motions without lateral rollers:
// corner_a = (0, 0) and corner_b = (L, 0) of the lower base and of the upper top.
Physical Point("lower_corner_a") = {lo_corner_a};
Physical Point("lower_corner_b") = {lo_corner_b};
Physical Point("upper_corner_a") = {up_corner_a};
Physical Point("upper_corner_b") = {up_corner_b};
