// ----------------------------------------------------------------------------
// two_discs_on_block_2d.geo -- internodes mesh: two elastic half discs side by
//                              side pressed into one block, 2D (plane strain);
//                              two contact pairs that share the block
// ----------------------------------------------------------------------------
//
// Models : in the xy plane (y up), the block [-W,W] x [-H,0] and two lower
//          half discs of radius R, their poles (lowest points) at (+-s/2, gap)
//          and their flat chords at y = R + gap. Three separate meshes (no
//          shared nodes). The model is mirror-symmetric about x = 0, and so
//          is the MESH: the right half (the block's half x >= 0 and the right
//          disc) is meshed, and the left half is its mirror image (Periodic
//          constraints with the reflection x -> -x), node for node, its
//          triangles turned back to counter-clockwise (Reverse Surface). gmsh
//          4.8.4 places a few nodes of the copied arcs up to 1e-7 R off the
//          exact image (measured: 7e-8 R at level 0, 8e-8 R at level 1; the
//          straight lines and the interiors to 1e-11); validation/multi_body.py
//          moves them onto it, after which a solve of the mirror-symmetric
//          case gives two pair forces that differ by round-off only. The
//          block's two halves are one body, conforming along x = 0 (the shared
//          line carries no group).
//          The poles and the block nodes under them are mesh nodes (the top
//          edge is split at x = +-s/2).
//
// Parameters (-setnumber name value; lengths in model units):
//   level  refinement level; every mesh size is multiplied by 2^-level     [0]
//   R      disc radius                                                     [1]
//   s      centre-to-centre distance of the discs                         [3 R]
//   gap    height of the poles above the block top (negative: overlap)   [0]
//   W      half-width of the block                                        [4 R]
//   H      height of the block                                            [2 R]
//   h_c    size within r_c of each pole / the block point under it    [R/80]
//   r_c    radius of the uniformly refined zone                           [R/5]
//   h_far  size far from the contact points                               [R/2]
//   d_far  distance from a contact point where h_far is reached           [2 R]
//   block_ratio  every block size = block_ratio x the disc's              [1]
//
// Run :    gmsh -2 two_discs_on_block_2d.geo -format msh41 -o tdob.msh
//
// Physical groups:
//
//       disc_left_top                     disc_right_top
//      +-------------+                   +-------------+        y = R + gap
//       \ disc_left /                     \ disc_right/
//        `-._____.-'  <- disc_left_contact `-._____.-'  <- disc_right_contact
//  (-W,0) +------o---------------+---------------o------+ (W,0)
//         | block_contact_left   |  block_contact_right |
//  block_ |   (x <= 0)         block (x >= 0)           | block_
//  sides  |                      |                      | sides
// (-W,-H) +----------------------+----------------------+ (W,-H)
//                            block_base
//
// Boundary lines of the right half run counter-clockwise around their body;
// the mirrored lines of the left half run the other way (the solver takes a
// facet's side from its cell).
// ----------------------------------------------------------------------------

DefineConstant[
  level = {0, Name "Parameters/level"},
  R = {1, Name "Parameters/R"},
  s = {3 * R, Name "Parameters/s"},
  gap = {0, Name "Parameters/gap"},
  W = {4 * R, Name "Parameters/W"},
  H = {2 * R, Name "Parameters/H"},
  h_c = {R / 80, Name "Parameters/h_c"},
  r_c = {R / 5, Name "Parameters/r_c"},
  h_far = {R / 2, Name "Parameters/h_far"},
  d_far = {2 * R, Name "Parameters/d_far"},
  block_ratio = {1, Name "Parameters/block_ratio"}
];

If (s / 2 - R <= 0 || s / 2 + R >= W)
  Error("two_discs_on_block_2d: the discs must lie apart and on the block (R < s/2 < W - R)");
EndIf

Geometry.AutoCoherence = 0; // never merge coincident points (bodies are disjoint)
f = 2 ^ (-level);
xc = s / 2;

// --- right half of the block [0, W] x [-H, 0], top edge split under the pole ----
b0 = newp; Point(b0) = {0, -H, 0};
b1 = newp; Point(b1) = {W, -H, 0};
b2 = newp; Point(b2) = {W, 0, 0};
b3 = newp; Point(b3) = {xc, 0, 0};
b4 = newp; Point(b4) = {0, 0, 0};
lb_base = newl; Line(lb_base) = {b0, b1};
lb_side = newl; Line(lb_side) = {b1, b2};
lb_top1 = newl; Line(lb_top1) = {b2, b3};
lb_top2 = newl; Line(lb_top2) = {b3, b4};
lb_mid = newl; Line(lb_mid) = {b4, b0};
cl = newll; Curve Loop(cl) = {lb_base, lb_side, lb_top1, lb_top2, lb_mid};
s_block_r = news; Plane Surface(s_block_r) = {cl};

// --- right disc: lower half of the disc of radius R centred at (xc, R + gap) ----
yc = R + gap;
d0 = newp; Point(d0) = {xc, yc, 0};      // centre
d1 = newp; Point(d1) = {xc, gap, 0};     // pole
d2 = newp; Point(d2) = {xc + R, yc, 0};
d3 = newp; Point(d3) = {xc - R, yc, 0};
a1 = newl; Circle(a1) = {d3, d0, d1};
a2 = newl; Circle(a2) = {d1, d0, d2};
l_chord = newl; Line(l_chord) = {d2, d3};
cl = newll; Curve Loop(cl) = {a1, a2, l_chord};
s_disc_r = news; Plane Surface(s_disc_r) = {cl};

// --- left half: the mirror image (x -> -x) of the right half ---------------------
// The block's left half shares the middle line x = 0 (and its end points) with the
// right half: one conforming body. Every other entity is the mirror of one on the
// right, and is declared periodic with it below, so that gmsh copies the mesh.
c0 = newp; Point(c0) = {-W, -H, 0};
c2 = newp; Point(c2) = {-W, 0, 0};
c3 = newp; Point(c3) = {-xc, 0, 0};
lc_base = newl; Line(lc_base) = {c0, b0};
lc_side = newl; Line(lc_side) = {c2, c0};
lc_top1 = newl; Line(lc_top1) = {c3, c2};
lc_top2 = newl; Line(lc_top2) = {b4, c3};
cl = newll; Curve Loop(cl) = {lc_base, -lb_mid, lc_top2, lc_top1, lc_side};
s_block_l = news; Plane Surface(s_block_l) = {cl};

e0 = newp; Point(e0) = {-xc, yc, 0};
e1 = newp; Point(e1) = {-xc, gap, 0};
e2 = newp; Point(e2) = {-xc - R, yc, 0};
e3 = newp; Point(e3) = {-xc + R, yc, 0};
c1 = newl; Circle(c1) = {e1, e0, e3};        // image of a1, backwards
c2a = newl; Circle(c2a) = {e2, e0, e1};      // image of a2, backwards
lc_chord = newl; Line(lc_chord) = {e3, e2};  // image of l_chord, backwards
cl = newll; Curve Loop(cl) = {c2a, c1, lc_chord};
s_disc_l = news; Plane Surface(s_disc_l) = {cl};

// --- mesh sizes: refinement towards the four contact points (symmetric) ------------
Field[2] = MathEval;
// distance to the nearer of the points (+-xc, 0) and (+-xc, gap): the field is an
// even function of x, so the mirrored half sees the same sizes
Field[2].F = Sprintf("Min(Sqrt((Fabs(x) - %g)^2 + y^2), Sqrt((Fabs(x) - %g)^2 + (y - %g)^2))", xc, xc, gap);
Field[3] = Threshold;              // discs
Field[3].InField = 2;
Field[3].SizeMin = h_c * f;
Field[3].SizeMax = h_far * f;
Field[3].DistMin = r_c;
Field[3].DistMax = d_far;
Field[4] = Threshold;              // block
Field[4].InField = 2;
Field[4].SizeMin = block_ratio * h_c * f;
Field[4].SizeMax = block_ratio * h_far * f;
Field[4].DistMin = r_c;
Field[4].DistMax = d_far;
Field[5] = Restrict;
Field[5].InField = 3;
Field[5].SurfacesList = {s_disc_r, s_disc_l};
Field[5].CurvesList = {a1, a2, l_chord, c1, c2a, lc_chord};
Field[6] = Restrict;
Field[6].InField = 4;
Field[6].SurfacesList = {s_block_r, s_block_l};
Field[6].CurvesList = {lb_base, lb_side, lb_top1, lb_top2, lb_mid, lc_base, lc_side, lc_top1, lc_top2};
Field[7] = Min;
Field[7].FieldsList = {5, 6};
Background Field = 7;

// --- the left half's mesh is the right half's mirror image ----------------------
mirror[] = {-1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
Periodic Curve {lc_base} = {lb_base} Affine {mirror[]};
Periodic Curve {lc_side} = {lb_side} Affine {mirror[]};
Periodic Curve {lc_top1} = {lb_top1} Affine {mirror[]};
Periodic Curve {lc_top2} = {lb_top2} Affine {mirror[]};
Periodic Curve {c1} = {a1} Affine {mirror[]};
Periodic Curve {c2a} = {a2} Affine {mirror[]};
Periodic Curve {lc_chord} = {l_chord} Affine {mirror[]};
Periodic Surface {s_block_l} = {s_block_r} Affine {mirror[]};
Periodic Surface {s_disc_l} = {s_disc_r} Affine {mirror[]};
// a mirrored triangle runs clockwise: turn the copies back to counter-clockwise, as
// the right half's (the block's two halves must agree: one orientation per body)
Reverse Surface {s_block_l, s_disc_l};

Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.Algorithm = 6; // Frontal-Delaunay
Mesh.ElementOrder = 1;

// --- physical groups ------------------------------------------------------------
Physical Surface("disc_right") = {s_disc_r};
Physical Surface("disc_left") = {s_disc_l};
Physical Surface("block") = {s_block_r, s_block_l};
Physical Curve("disc_right_contact") = {a1, a2};
Physical Curve("disc_right_top") = {l_chord};
Physical Curve("disc_left_contact") = {c1, c2a};
Physical Curve("disc_left_top") = {lc_chord};
Physical Curve("block_contact_right") = {lb_top1, lb_top2};
Physical Curve("block_contact_left") = {lc_top1, lc_top2};
Physical Curve("block_base") = {lb_base, lc_base};
Physical Curve("block_sides") = {lb_side, lc_side};
