// ----------------------------------------------------------------------------
// half_disc_in_groove.geo -- internodes mesh: 2D (plane strain) Hertz contact,
//                            elastic half disc pressed into a concave groove
//                            of larger radius in an elastic block
// ----------------------------------------------------------------------------
//
// Models : in the xy plane (y up), the lower half of the disc of radius R
//          centred at (0,R+gap): its pole (lowest point) is at (0,gap) and its
//          flat chord at y = R + gap. It sits in the block whose top edge is
//          the groove, the arc of the circle of radius R_g > R centred at
//          (0,R_g) between x = -W and x = W (its lowest point is the origin),
//          and whose base is y = -H. The surfaces are conforming: Hertz with
//          the effective radius 1/R_eff = 1/R - 1/R_g (R_eff = 1.5 R with the
//          defaults), a contact half-width a ~ 0.12 R for an approach of
//          0.02 R. With gap = 0 the bodies touch at the origin only; gap < 0
//          is an initial overlap. The two meshes are independent (no shared
//          nodes, not even at the origin). The pole and the origin are mesh
//          nodes (curves are split there).
//
// Parameters (override with  -setnumber name value; lengths in model units):
//   level  refinement level (integer, may be negative to coarsen);
//          every mesh size below is multiplied by 2^-level          [0]
//   R      disc radius                                               [1]
//   R_g    groove radius (> R, and > W so the groove is one arc)     [3 R]
//   gap    height of the pole above the groove bottom (neg. = overlap) [0]
//   W      half-width of the block                                   [2 R]
//   H      depth of the block's base below the groove bottom         [2 R]
//   h_c    mesh size within distance r_c of the origin / the pole
//          (level 0)                                                 [R/40]
//   h_far  mesh size far from the contact point (level 0)            [R/2]
//   r_c    radius of the uniformly refined contact zone              [R/4]
//   d_far  distance from the contact point where h_far is reached;
//          linear growth from h_c at r_c                             [2 R]
//   block_ratio  block sizes = block_ratio * the sizes above, which
//          then apply to the disc only                               [1]
//
// Run :    gmsh -2 half_disc_in_groove.geo -format msh41 -o hdig.msh
//
// Physical groups (P1: 3-node triangles, 2-node lines):
//
//                            disc_top (y = R + gap, chord)
//                  (-R,R+gap) +-------------------+ (R,R+gap)
//   (-W,y_W) +                 \                 /                 + (W,y_W)
//            |`.                `.    disc     .'  <- disc_contact .'|
//            |   `-.              `-._______.-'   (whole lower arc) |
//   block_   |      `--.._              o pole (0,gap)       _..--'  | block_
//   sides    |            ``--..________o________..--''              | sides
//            |         block_contact (whole groove arc, lowest at 0)  |
//            |                       block                           |
//   (-W,-H)  +-------------------------------------------------------+ (W,-H)
//                                 block_base
//
//   y_W = R_g - sqrt(R_g^2 - W^2), the height of the groove's ends.
//
// Boundary lines are oriented counter-clockwise around their body (the body
// is on the left of each line, outward normal = (dy, -dx)).
// ----------------------------------------------------------------------------

DefineConstant[
  level = {0, Name "Parameters/level"},
  R = {1, Name "Parameters/R"},
  R_g = {3 * R, Name "Parameters/R_g"},
  gap = {0, Name "Parameters/gap"},
  W = {2 * R, Name "Parameters/W"},
  H = {2 * R, Name "Parameters/H"},
  h_c = {R / 40, Name "Parameters/h_c"},
  h_far = {R / 2, Name "Parameters/h_far"},
  r_c = {R / 4, Name "Parameters/r_c"},
  d_far = {2 * R, Name "Parameters/d_far"},
  block_ratio = {1, Name "Parameters/block_ratio"}
];

If (R_g <= R || R_g <= W)
  Error("half_disc_in_groove: the groove radius R_g = %g must exceed R = %g and W = %g", R_g, R, W);
  Abort;
EndIf

Geometry.AutoCoherence = 0; // never merge coincident points (bodies are disjoint)
s = 2 ^ (-level);           // size factor of this refinement level

// --- block: base y = -H, sides x = +-W, the groove on top split at the origin ----
y_W = R_g - Sqrt(R_g ^ 2 - W ^ 2);
p0 = newp; Point(p0) = {0, 0, 0};
p1 = newp; Point(p1) = {-W, -H, 0};
p2 = newp; Point(p2) = {W, -H, 0};
p3 = newp; Point(p3) = {W, y_W, 0};
p4 = newp; Point(p4) = {-W, y_W, 0};
pg = newp; Point(pg) = {0, R_g, 0};   // centre of the groove
l_base = newl; Line(l_base) = {p1, p2};
l_right = newl; Line(l_right) = {p2, p3};
l_top1 = newl; Circle(l_top1) = {p3, pg, p0};
l_top2 = newl; Circle(l_top2) = {p0, pg, p4};
l_left = newl; Line(l_left) = {p4, p1};
cl = newll; Curve Loop(cl) = {l_base, l_right, l_top1, l_top2, l_left};
s_block = news; Plane Surface(s_block) = {cl};

// --- half disc: lower half of the disc of radius R centred at (0, R+gap) --------
yc = R + gap;
q0 = newp; Point(q0) = {0, yc, 0};     // centre
q1 = newp; Point(q1) = {0, gap, 0};    // pole
q2 = newp; Point(q2) = {R, yc, 0};
q3 = newp; Point(q3) = {-R, yc, 0};
a1 = newl; Circle(a1) = {q3, q0, q1};
a2 = newl; Circle(a2) = {q1, q0, q2};
l_chord = newl; Line(l_chord) = {q2, q3};
cl = newll; Curve Loop(cl) = {a1, a2, l_chord};
s_disc = news; Plane Surface(s_disc) = {cl};

// --- mesh size: refinement towards the contact point -----------------------------
// Each body's sizes are restricted to its own entities, so the block can be coarser.
Field[1] = Distance;
Field[1].PointsList = {p0, q1};
Field[2] = Threshold;              // disc
Field[2].InField = 1;
Field[2].SizeMin = h_c * s;
Field[2].SizeMax = h_far * s;
Field[2].DistMin = r_c;
Field[2].DistMax = d_far;
Field[3] = Threshold;              // block (block_ratio x coarser)
Field[3].InField = 1;
Field[3].SizeMin = block_ratio * h_c * s;
Field[3].SizeMax = block_ratio * h_far * s;
Field[3].DistMin = r_c;
Field[3].DistMax = d_far;
Field[4] = Restrict;
Field[4].InField = 2;
Field[4].SurfacesList = {s_disc};
Field[4].CurvesList = {a1, a2, l_chord};
Field[4].PointsList = {q1, q2, q3};
Field[5] = Restrict;
Field[5].InField = 3;
Field[5].SurfacesList = {s_block};
Field[5].CurvesList = {l_base, l_right, l_top1, l_top2, l_left};
Field[5].PointsList = {p0, p1, p2, p3, p4};
Field[6] = Min;
Field[6].FieldsList = {4, 5};
Background Field = 6;

Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.Algorithm = 6; // Frontal-Delaunay
Mesh.ElementOrder = 1;

// --- physical groups ------------------------------------------------------------
Physical Surface("disc") = {s_disc};
Physical Surface("block") = {s_block};
Physical Curve("disc_contact") = {a1, a2};
Physical Curve("disc_top") = {l_chord};
Physical Curve("block_contact") = {l_top1, l_top2};
Physical Curve("block_base") = {l_base};
Physical Curve("block_sides") = {l_right, l_left};
