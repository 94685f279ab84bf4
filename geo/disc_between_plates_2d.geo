// ----------------------------------------------------------------------------
// disc_between_plates_2d.geo -- internodes mesh: an elastic disc between two
//                               elastic plates, 2D (plane strain), half model
//                               about the symmetry line x = 0: two contact
//                               pairs, the disc held only by them
// ----------------------------------------------------------------------------
//
// Models : in the xy plane (y up), the right half (x >= 0) of the disc of
//          radius R centred at (0, R): its poles (0, 0) and (0, 2R) lie on the
//          symmetry line. Below it the plate [0, W] x [-H, gap_b], its top
//          face y = gap_b (0: touching the lower pole; negative: overlap);
//          above it the plate [0, W] x [2R + gap_t, 2R + gap_t + H]. Three
//          separate meshes (no shared nodes). The symmetry line carries a
//          group on every body (ux = 0 there holds the lateral motion and the
//          rotation of each: what frictionless contact cannot hold on a round
//          body). The poles and the plate points under / above them are mesh
//          nodes (the end points of the lines).
//
// Parameters (-setnumber name value; lengths in model units):
//   level  every mesh size is multiplied by 2^-level                      [0]
//   R      disc radius                                                     [1]
//   W      plate width (the half model's: the full plate is 2W wide)     [2 R]
//   H      plate thickness                                                [R]
//   gap_b, gap_t  initial gaps at the lower and upper pole (neg.: overlap) [0, 0]
//   h_c    mesh size within r_c of each pole / the plate point at it  [R/80]
//   r_c    radius of the uniformly refined zones                          [R/5]
//   h_far  mesh size far from the contact points                         [R/4]
//   d_far  distance from a contact point where h_far is reached          [R]
//
// Run :    gmsh -2 disc_between_plates_2d.geo -format msh41 -o dbp.msh
//
// Physical groups:
//
//                       top_load (y = 2R + gap_t + H)
//              +-----------------------------+
//     top_axis |            top              | top_side
//              +-----------------------------+ (W, 2R + gap_t)
//              ^ top_contact (y = 2R + gap_t)
//              o (0, 2R)
//      disc_   | `-.  <- disc_upper (upper quarter arc)
//      axis    |  disc )  (R, R)
//      (x = 0) | .-'  <- disc_lower (lower quarter arc)
//              o (0, 0)
//              v bottom_contact (y = gap_b)
//              +-----------------------------+ (W, gap_b)
//  bottom_axis |           bottom            | bottom_side
//              +-----------------------------+
//                     bottom_base (y = -H)
//
// Lines run counter-clockwise around their body (outward normal (dy, -dx)).
// ----------------------------------------------------------------------------

DefineConstant[
  level = {0, Name "Parameters/level"},
  R = {1, Name "Parameters/R"},
  W = {2 * R, Name "Parameters/W"},
  H = {R, Name "Parameters/H"},
  gap_b = {0, Name "Parameters/gap_b"},
  gap_t = {0, Name "Parameters/gap_t"},
  h_c = {R / 80, Name "Parameters/h_c"},
  r_c = {R / 5, Name "Parameters/r_c"},
  h_far = {R / 4, Name "Parameters/h_far"},
  d_far = {R, Name "Parameters/d_far"}
];

Geometry.AutoCoherence = 0; // never merge coincident points (bodies are disjoint)
f = 2 ^ (-level);
y_top = 2 * R + gap_t;

// --- bottom plate [0, W] x [-H, gap_b] ----------------------------------------------
p1 = newp; Point(p1) = {0, -H, 0};
p2 = newp; Point(p2) = {W, -H, 0};
p3 = newp; Point(p3) = {W, gap_b, 0};
p4 = newp; Point(p4) = {0, gap_b, 0};
lb_base = newl; Line(lb_base) = {p1, p2};
lb_side = newl; Line(lb_side) = {p2, p3};
lb_top = newl; Line(lb_top) = {p3, p4};
lb_axis = newl; Line(lb_axis) = {p4, p1};
cl = newll; Curve Loop(cl) = {lb_base, lb_side, lb_top, lb_axis};
s_bottom = news; Plane Surface(s_bottom) = {cl};

// --- half disc: x >= 0 half of the disc of radius R centred at (0, R) ----------------
q0 = newp; Point(q0) = {0, R, 0};       // centre
q1 = newp; Point(q1) = {0, 0, 0};       // lower pole
q2 = newp; Point(q2) = {R, R, 0};       // equator
q3 = newp; Point(q3) = {0, 2 * R, 0};   // upper pole
a_low = newl; Circle(a_low) = {q1, q0, q2};
a_up = newl; Circle(a_up) = {q2, q0, q3};
l_axis = newl; Line(l_axis) = {q3, q1};
cl = newll; Curve Loop(cl) = {a_low, a_up, l_axis};
s_disc = news; Plane Surface(s_disc) = {cl};

// --- top plate [0, W] x [2R + gap_t, 2R + gap_t + H] ---------------------------------
r1 = newp; Point(r1) = {0, y_top, 0};
r2 = newp; Point(r2) = {W, y_top, 0};
r3 = newp; Point(r3) = {W, y_top + H, 0};
r4 = newp; Point(r4) = {0, y_top + H, 0};
lt_contact = newl; Line(lt_contact) = {r1, r2};
lt_side = newl; Line(lt_side) = {r2, r3};
lt_load = newl; Line(lt_load) = {r3, r4};
lt_axis = newl; Line(lt_axis) = {r4, r1};
cl = newll; Curve Loop(cl) = {lt_contact, lt_side, lt_load, lt_axis};
s_top = news; Plane Surface(s_top) = {cl};

// --- mesh size: refinement towards the two contact points ----------------------------
Field[1] = Distance;
Field[1].PointsList = {p4, q1, q3, r1};
Field[2] = Threshold;
Field[2].InField = 1;
Field[2].SizeMin = h_c * f;
Field[2].SizeMax = h_far * f;
Field[2].DistMin = r_c;
Field[2].DistMax = d_far;
Background Field = 2;

Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.Algorithm = 6; // Frontal-Delaunay
Mesh.ElementOrder = 1;

// --- physical groups ------------------------------------------------------------
Physical Surface("bottom") = {s_bottom};
Physical Surface("disc") = {s_disc};
Physical Surface("top") = {s_top};
Physical Curve("bottom_base") = {lb_base};
Physical Curve("bottom_side") = {lb_side};
Physical Curve("bottom_contact") = {lb_top};
Physical Curve("bottom_axis") = {lb_axis};
Physical Curve("disc_lower") = {a_low};
Physical Curve("disc_upper") = {a_up};
Physical Curve("disc_axis") = {l_axis};
Physical Curve("top_contact") = {lt_contact};
Physical Curve("top_side") = {lt_side};
Physical Curve("top_load") = {lt_load};
Physical Curve("top_axis") = {lt_axis};
