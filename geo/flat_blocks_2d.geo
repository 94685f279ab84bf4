// ----------------------------------------------------------------------------
// flat_blocks_2d.geo -- internodes mesh: two flat blocks pressed together,
//                       2D (plane strain), non-matching meshes; or their union
// ----------------------------------------------------------------------------
//
// Models : lower block [-W_l, W_l] x [-H_l, 0] and upper block
//          [-W_u, W_u] x [gap, gap + H_u], centred on the same vertical axis
//          x = 0. gap = 0: the flat faces touch on y = 0 (the upper one as wide
//          or narrower than the lower one, or wider); gap < 0: the upper block
//          is meshed -gap into the lower one. Uniform (unstructured) mesh sizes
//          h_l and h_u, so the two faces do not match unless h_u = h_l. The
//          bodies are disjoint meshes (no shared nodes). The base centre
//          (0, -H_l) and the top centre (0, gap + H_u) are mesh nodes, named
//          as points, to pin the blocks against the horizontal rigid motion
//          when their ends slide freely.
//          union = 1: the same two rectangles (W_u = W_l, gap = 0 required)
//          meshed as ONE body `union` with a conforming interface y = 0 (the
//          reference for the symmetric set-ups: total height H_l + H_u).
//
// Parameters (override with  -setnumber name value; lengths in model units):
//   level  refinement level (integer, may be negative to coarsen);
//          every mesh size below is multiplied by 2^-level          [0]
//   W_l    half-width of the lower block                            [1]
//   W_u    half-width of the upper block                            [W_l]
//   H_l    height of the lower block                                [0.5]
//   H_u    height of the upper block                                [0.5]
//   gap    height of the upper block's face above y = 0 (neg.:
//          meshed overlapping)                                      [0]
//   h_l    mesh size of the lower block (level 0)                    [1/20]
//   h_u    mesh size of the upper block (level 0)                    [h_l]
//   union  1: one body `union`, conforming interface                [0]
//
// Run :    gmsh -2 flat_blocks_2d.geo -format msh41 -o fb2.msh
//          gmsh -2 flat_blocks_2d.geo -setnumber h_u 0.01 -setnumber gap -0.005 -o fb2o.msh
//          gmsh -2 flat_blocks_2d.geo -setnumber union 1 -setnumber h_l 0.0125 -o fb2u.msh
//
// Physical groups (P1: 3-node triangles, 2-node lines):
//
//                              upper_top (y = gap + H_u)
//               (-W_u,.) +-------------o-------------+ (W_u,.)
//                        |         upper_pin         |
//          upper_sides   |           upper           |  upper_sides
//                        |                           |
//             (-W_u,gap) +---------------------------+ (W_u,gap) <- upper_contact
//   (-W_l,0) +-----------------------------------------------+ (W_l,0) <- lower_contact
//            |                                               |
//  lower_    |                     lower                     | lower_
//  sides     |                                               | sides
//            |                  lower_pin                    |
//  (-W_l,-H_l)+----------------------o------------------------+ (W_l,-H_l)
//                               lower_base
//
//   union = 1: Physical Surface "union" (both rectangles, one body), Physical
//   Curve "interface" (y = 0), and lower_base, upper_top, lower_sides,
//   upper_sides, lower_pin, upper_pin as above (no lower/upper bodies, no
//   *_contact groups).
//
// Boundary lines are oriented counter-clockwise around their body (the body
// is on the left of each line, outward normal = (dy, -dx)).
// ----------------------------------------------------------------------------

DefineConstant[
  level = {0, Name "Parameters/level"},
  W_l = {1, Name "Parameters/W_l"},
  W_u = {W_l, Name "Parameters/W_u"},
  H_l = {0.5, Name "Parameters/H_l"},
  H_u = {0.5, Name "Parameters/H_u"},
  gap = {0, Name "Parameters/gap"},
  h_l = {1 / 20, Name "Parameters/h_l"},
  h_u = {h_l, Name "Parameters/h_u"},
  union = {0, Name "Parameters/union"}
];

If (union && (W_u != W_l || gap != 0))
  Error("flat_blocks_2d.geo: union = 1 needs W_u = W_l and gap = 0");
  Abort;
EndIf

Geometry.AutoCoherence = 0; // never merge coincident points (bodies are disjoint)
s = 2 ^ (-level);           // size factor of this refinement level
sl = h_l * s;
su = h_u * s;

// --- lower block [-W_l, W_l] x [-H_l, 0], base split at its centre -----------------
p1 = newp; Point(p1) = {-W_l, -H_l, 0, sl};
p2 = newp; Point(p2) = {0, -H_l, 0, sl};
p3 = newp; Point(p3) = {W_l, -H_l, 0, sl};
p4 = newp; Point(p4) = {W_l, 0, 0, sl};
p5 = newp; Point(p5) = {-W_l, 0, 0, sl};
l_base1 = newl; Line(l_base1) = {p1, p2};
l_base2 = newl; Line(l_base2) = {p2, p3};
l_right = newl; Line(l_right) = {p3, p4};
l_top = newl; Line(l_top) = {p4, p5};
l_left = newl; Line(l_left) = {p5, p1};
cl = newll; Curve Loop(cl) = {l_base1, l_base2, l_right, l_top, l_left};
s_lower = news; Plane Surface(s_lower) = {cl};

// --- upper block [-W_u, W_u] x [gap, gap + H_u], top split at its centre -----------
yt = gap + H_u;
If (union)
  // the same rectangle sharing the lower block's top line: one conforming mesh
  q1 = p5; q2 = p4;
  u_bottom = -l_top;
Else
  q1 = newp; Point(q1) = {-W_u, gap, 0, su};
  q2 = newp; Point(q2) = {W_u, gap, 0, su};
  u_bottom = newl; Line(u_bottom) = {q1, q2};
EndIf
q3 = newp; Point(q3) = {W_u, yt, 0, su};
q4 = newp; Point(q4) = {0, yt, 0, su};
q5 = newp; Point(q5) = {-W_u, yt, 0, su};
u_right = newl; Line(u_right) = {q2, q3};
u_top1 = newl; Line(u_top1) = {q3, q4};
u_top2 = newl; Line(u_top2) = {q4, q5};
u_left = newl; Line(u_left) = {q5, q1};
cl = newll; Curve Loop(cl) = {u_bottom, u_right, u_top1, u_top2, u_left};
s_upper = news; Plane Surface(s_upper) = {cl};

// --- mesh size: uniform per body (from the point sizes) ----------------------------
Mesh.MeshSizeFromPoints = 1;
Mesh.MeshSizeFromCurvature = 0;
Mesh.MeshSizeExtendFromBoundary = 1;
Mesh.Algorithm = 6; // Frontal-Delaunay
Mesh.ElementOrder = 1;

// --- physical groups ------------------------------------------------------------
If (union)
  Physical Surface("union") = {s_lower, s_upper};
  Physical Curve("interface") = {l_top};
Else
  Physical Surface("lower") = {s_lower};
  Physical Surface("upper") = {s_upper};
  Physical Curve("lower_contact") = {l_top};
  Physical Curve("upper_contact") = {u_bottom};
EndIf
Physical Curve("lower_base") = {l_base1, l_base2};
Physical Curve("upper_top") = {u_top1, u_top2};
Physical Curve("lower_sides") = {l_right, l_left};
Physical Curve("upper_sides") = {u_right, u_left};
Physical Point("lower_pin") = {p2};
Physical Point("upper_pin") = {q4};
