// ----------------------------------------------------------------------------
// three_blocks_2d.geo -- internodes mesh: three stacked blocks, 2D (plane
//                        strain), non-matching meshes on two flat interfaces
// ----------------------------------------------------------------------------
//
// Models : lower [0,L] x [-H,0], middle [0,L] x [0,H], upper [0,L] x [H,2H],
//          separate geometric entities (no shared nodes), each meshed with its
//          own size, so that neither interface mesh matches. Two contact pairs
//          share the middle block: the exact solution of the stack pressed on
//          rollers is a uniform stress (a patch test of several pairs).
//
// Parameters (-setnumber name value):
//   level  refinement level; every mesh size is multiplied by 2^-level   [0]
//   L, H   width and height of each block                               [1, 1]
//   h_l, h_m, h_u  mesh sizes of the lower, middle, upper block  [1/5, 1/7, 1/6]
//          (the middle block finest: the compliant outer blocks are the primaries,
//          and a coarser primary gets the exact interpolation transfer)
//
// Physical groups: bodies lower, middle, upper; lines lower_base,
// lower_contact (y = 0), middle_bottom (y = 0), middle_top (y = H),
// upper_contact (y = H), upper_top (y = 2H), and each body's sides
// (lower_sides, middle_sides, upper_sides).
// ----------------------------------------------------------------------------

DefineConstant[
  level = {0, Name "Parameters/level"},
  L = {1, Name "Parameters/L"},
  H = {1, Name "Parameters/H"},
  h_l = {1 / 5, Name "Parameters/h_l"},
  h_m = {1 / 7, Name "Parameters/h_m"},
  h_u = {1 / 6, Name "Parameters/h_u"}
];
f = 2^(-level);

// Each block [0,L] x [y0, y0 + H]: four points and four lines, counter-
// clockwise from the bottom (the body on the left of each line).

// lower
Point(1) = {0, -H, 0, h_l * f};
Point(2) = {L, -H, 0, h_l * f};
Point(3) = {L, -H + H, 0, h_l * f};
Point(4) = {0, -H + H, 0, h_l * f};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
Physical Surface("lower") = {1};
Physical Curve("lower_base") = {1};
Physical Curve("lower_sides") = {2, 4};
Physical Curve("lower_contact") = {3};

// middle
Point(11) = {0, 0, 0, h_m * f};
Point(12) = {L, 0, 0, h_m * f};
Point(13) = {L, 0 + H, 0, h_m * f};
Point(14) = {0, 0 + H, 0, h_m * f};
Line(11) = {11, 12};
Line(12) = {12, 13};
Line(13) = {13, 14};
Line(14) = {14, 11};
Curve Loop(11) = {11, 12, 13, 14};
Plane Surface(11) = {11};
Physical Surface("middle") = {11};
Physical Curve("middle_bottom") = {11};
Physical Curve("middle_sides") = {12, 14};
Physical Curve("middle_top") = {13};

// upper
Point(21) = {0, H, 0, h_u * f};
Point(22) = {L, H, 0, h_u * f};
Point(23) = {L, H + H, 0, h_u * f};
Point(24) = {0, H + H, 0, h_u * f};
Line(21) = {21, 22};
Line(22) = {22, 23};
Line(23) = {23, 24};
Line(24) = {24, 21};
Curve Loop(21) = {21, 22, 23, 24};
Plane Surface(21) = {21};
Physical Surface("upper") = {21};
Physical Curve("upper_contact") = {21};
Physical Curve("upper_sides") = {22, 24};
Physical Curve("upper_top") = {23};

Mesh.ElementOrder = 1;
