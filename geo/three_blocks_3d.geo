// ----------------------------------------------------------------------------
// three_blocks_3d.geo -- internodes mesh: three stacked blocks, 3D, non-matching
//                        meshes on two flat interfaces
// ----------------------------------------------------------------------------
//
// The 3D twin of three_blocks_2d.geo: lower [0,L]^2 x [-H,0], middle [0,L]^2 x
// [0,H], upper [0,L]^2 x [H,2H], separate volumes (no shared points, so no
// shared nodes: built-in kernel, each block its own eight points), each meshed
// with its own size. Two contact pairs share the middle block.
//
// Parameters (-setnumber name value):
//   level  refinement level; every mesh size is multiplied by 2^-level   [0]
//   L, H   width and height of each block                               [1, 1]
//   h_l, h_m, h_u  mesh sizes of the lower, middle, upper block  [1/3, 1/5, 1/4]
//          (the middle block finest: the compliant outer blocks are the primaries,
//          and a coarser primary gets the exact interpolation transfer)
//
// Physical groups: volumes lower, middle, upper; surfaces lower_base,
// lower_contact (z = 0), middle_bottom (z = 0), middle_top (z = H),
// upper_contact (z = H), upper_top (z = 2H), and each body's four sides
// (lower_sides, middle_sides, upper_sides). Surfaces are oriented outward.
// ----------------------------------------------------------------------------

DefineConstant[
  level = {0, Name "Parameters/level"},
  L = {1, Name "Parameters/L"},
  H = {1, Name "Parameters/H"},
  h_l = {1 / 3, Name "Parameters/h_l"},
  h_m = {1 / 5, Name "Parameters/h_m"},
  h_u = {1 / 4, Name "Parameters/h_u"}
];
f = 2^(-level);

// lower: points 1-4 at the bottom, 5-8 at the top (counter-clockwise seen from above)
Point(1) = {0, 0, -H, h_l * f};
Point(2) = {L, 0, -H, h_l * f};
Point(3) = {L, L, -H, h_l * f};
Point(4) = {0, L, -H, h_l * f};
Point(5) = {0, 0, -H + H, h_l * f};
Point(6) = {L, 0, -H + H, h_l * f};
Point(7) = {L, L, -H + H, h_l * f};
Point(8) = {0, L, -H + H, h_l * f};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 1};
Line(5) = {5, 6};
Line(6) = {6, 7};
Line(7) = {7, 8};
Line(8) = {8, 5};
Line(9) = {1, 5};
Line(10) = {2, 6};
Line(11) = {3, 7};
Line(12) = {4, 8};
Curve Loop(1) = {-4, -3, -2, -1};
Plane Surface(1) = {1};
Curve Loop(2) = {5, 6, 7, 8};
Plane Surface(2) = {2};
Curve Loop(3) = {1, 10, -5, -9};
Plane Surface(3) = {3};
Curve Loop(4) = {2, 11, -6, -10};
Plane Surface(4) = {4};
Curve Loop(5) = {3, 12, -7, -11};
Plane Surface(5) = {5};
Curve Loop(6) = {4, 9, -8, -12};
Plane Surface(6) = {6};
Surface Loop(1) = {1, 2, 3, 4, 5, 6};
Volume(1) = {1};
Physical Volume("lower") = {1};
Physical Surface("lower_base") = {1};
Physical Surface("lower_sides") = {3, 4, 5, 6};
Physical Surface("lower_contact") = {2};

// middle: points 1-4 at the bottom, 5-8 at the top (counter-clockwise seen from above)
Point(101) = {0, 0, 0, h_m * f};
Point(102) = {L, 0, 0, h_m * f};
Point(103) = {L, L, 0, h_m * f};
Point(104) = {0, L, 0, h_m * f};
Point(105) = {0, 0, 0 + H, h_m * f};
Point(106) = {L, 0, 0 + H, h_m * f};
Point(107) = {L, L, 0 + H, h_m * f};
Point(108) = {0, L, 0 + H, h_m * f};
Line(101) = {101, 102};
Line(102) = {102, 103};
Line(103) = {103, 104};
Line(104) = {104, 101};
Line(105) = {105, 106};
Line(106) = {106, 107};
Line(107) = {107, 108};
Line(108) = {108, 105};
Line(109) = {101, 105};
Line(110) = {102, 106};
Line(111) = {103, 107};
Line(112) = {104, 108};
Curve Loop(101) = {-104, -103, -102, -101};
Plane Surface(101) = {101};
Curve Loop(102) = {105, 106, 107, 108};
Plane Surface(102) = {102};
Curve Loop(103) = {101, 110, -105, -109};
Plane Surface(103) = {103};
Curve Loop(104) = {102, 111, -106, -110};
Plane Surface(104) = {104};
Curve Loop(105) = {103, 112, -107, -111};
Plane Surface(105) = {105};
Curve Loop(106) = {104, 109, -108, -112};
Plane Surface(106) = {106};
Surface Loop(101) = {101, 102, 103, 104, 105, 106};
Volume(101) = {101};
Physical Volume("middle") = {101};
Physical Surface("middle_bottom") = {101};
Physical Surface("middle_sides") = {103, 104, 105, 106};
Physical Surface("middle_top") = {102};

// upper: points 1-4 at the bottom, 5-8 at the top (counter-clockwise seen from above)
Point(201) = {0, 0, H, h_u * f};
Point(202) = {L, 0, H, h_u * f};
Point(203) = {L, L, H, h_u * f};
Point(204) = {0, L, H, h_u * f};
Point(205) = {0, 0, H + H, h_u * f};
Point(206) = {L, 0, H + H, h_u * f};
Point(207) = {L, L, H + H, h_u * f};
Point(208) = {0, L, H + H, h_u * f};
Line(201) = {201, 202};
Line(202) = {202, 203};
Line(203) = {203, 204};
Line(204) = {204, 201};
Line(205) = {205, 206};
Line(206) = {206, 207};
Line(207) = {207, 208};
Line(208) = {208, 205};
Line(209) = {201, 205};
Line(210) = {202, 206};
Line(211) = {203, 207};
Line(212) = {204, 208};
Curve Loop(201) = {-204, -203, -202, -201};
Plane Surface(201) = {201};
Curve Loop(202) = {205, 206, 207, 208};
Plane Surface(202) = {202};
Curve Loop(203) = {201, 210, -205, -209};
Plane Surface(203) = {203};
Curve Loop(204) = {202, 211, -206, -210};
Plane Surface(204) = {204};
Curve Loop(205) = {203, 212, -207, -211};
Plane Surface(205) = {205};
Curve Loop(206) = {204, 209, -208, -212};
Plane Surface(206) = {206};
Surface Loop(201) = {201, 202, 203, 204, 205, 206};
Volume(201) = {201};
Physical Volume("upper") = {201};
Physical Surface("upper_contact") = {201};
Physical Surface("upper_sides") = {203, 204, 205, 206};
Physical Surface("upper_top") = {202};

Mesh.ElementOrder = 1;
