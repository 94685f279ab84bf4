// ----------------------------------------------------------------------------
// stack_2d.geo -- internodes mesh: three blocks stacked, 2D (plane strain), each
//                 meshed with its own size: two flat interfaces, two contact
//                 pairs, neither interface mesh matching
// ----------------------------------------------------------------------------
//
// Models : bottom [0,L] x [0,H_b], middle [0,L] x [H_b, H_b+H_m], top
//          [0,L] x [H_b+H_m, H_b+H_m+H_t]: three separate meshes (no shared
//          nodes, not even on the interfaces). Held on rollers on their left
//          sides (x = 0) and the bottom block's base, the top block's top
//          pushed down, the stack is in uniform uniaxial stress: each block's
//          exact displacement is linear, which P1 represents exactly (a
//          patch test of several contact pairs; validation/multi_body.py).
//          Every mesh size is uniform per block (point sizes).
//
// Parameters (-setnumber name value):
//   level            every mesh size is multiplied by 2^-level          [0]
//   L                width of the blocks                                 [1]
//   H_b, H_m, H_t    heights of the bottom, middle, top block    [0.6, 0.5, 0.4]
//   h_b, h_m, h_t    mesh sizes of the bottom, middle, top block
//                                                         [1/10, 1/13, 1/8]
//
// Run :    gmsh -2 stack_2d.geo -format msh41 -o stack_2d.msh
//
// Physical groups: bodies bottom, middle, top; lines
//
//            top_load (y = H_b+H_m+H_t)
//          +-----------+
//  top_left|    top    |top_right
//          +-----------+ top_bottom     (y = H_b+H_m)
//          +-----------+ middle_top     (y = H_b+H_m)
//  middle_ |  middle   | middle_right
//  left    +-----------+ middle_bottom  (y = H_b)
//          +-----------+ bottom_top     (y = H_b)
//  bottom_ |  bottom   | bottom_right
//  left    +-----------+
//            bottom_base (y = 0)
//
// Lines run counter-clockwise around their body (outward normal (dy, -dx)).
// ----------------------------------------------------------------------------

DefineConstant[
  level = {0, Name "Parameters/level"},
  L = {1, Name "Parameters/L"},
  H_b = {0.6, Name "Parameters/H_b"},
  H_m = {0.5, Name "Parameters/H_m"},
  H_t = {0.4, Name "Parameters/H_t"},
  h_b = {1 / 10, Name "Parameters/h_b"},
  h_m = {1 / 13, Name "Parameters/h_m"},
  h_t = {1 / 8, Name "Parameters/h_t"}
];

Geometry.AutoCoherence = 0; // never merge coincident points (bodies are disjoint)
f = 2 ^ (-level);

// One block [0, L] x [y0, y0 + h], mesh size lc: its surface and its four lines
// (bottom, right, top, left), counter-clockwise.
Macro OneBlock
  p1 = newp; Point(p1) = {0, y0, 0, lc};
  p2 = newp; Point(p2) = {L, y0, 0, lc};
  p3 = newp; Point(p3) = {L, y0 + h, 0, lc};
  p4 = newp; Point(p4) = {0, y0 + h, 0, lc};
  l_bottom = newl; Line(l_bottom) = {p1, p2};
  l_right = newl; Line(l_right) = {p2, p3};
  l_top = newl; Line(l_top) = {p3, p4};
  l_left = newl; Line(l_left) = {p4, p1};
  loop = newll; Curve Loop(loop) = {l_bottom, l_right, l_top, l_left};
  surface = news; Plane Surface(surface) = {loop};
Return

y0 = 0; h = H_b; lc = h_b * f;
Call OneBlock;
Physical Surface("bottom") = {surface};
Physical Curve("bottom_base") = {l_bottom};
Physical Curve("bottom_right") = {l_right};
Physical Curve("bottom_top") = {l_top};
Physical Curve("bottom_left") = {l_left};

y0 = H_b; h = H_m; lc = h_m * f;
Call OneBlock;
Physical Surface("middle") = {surface};
Physical Curve("middle_bottom") = {l_bottom};
Physical Curve("middle_right") = {l_right};
Physical Curve("middle_top") = {l_top};
Physical Curve("middle_left") = {l_left};

y0 = H_b + H_m; h = H_t; lc = h_t * f;
Call OneBlock;
Physical Surface("top") = {surface};
Physical Curve("top_bottom") = {l_bottom};
Physical Curve("top_right") = {l_right};
Physical Curve("top_load") = {l_top};
Physical Curve("top_left") = {l_left};

Mesh.Algorithm = 6; // Frontal-Delaunay
Mesh.ElementOrder = 1;
