// ----------------------------------------------------------------------------
// two_half_discs.geo -- internodes mesh: 2D (plane strain) Hertz contact
//                       between two elastic half discs, pole against pole
// ----------------------------------------------------------------------------
//
// Models : in the xy plane (y up):
//          lower body = upper half of the disc of radius R_l centred at
//          (0,-R_l): pole up at the origin, flat chord at y = -R_l;
//          upper body = lower half of the disc of radius R_u centred at
//          (0,R_u+gap): pole down at (0,gap), flat chord at y = R_u + gap.
//          With gap = 0 the bodies touch at the origin only; gap < 0 is an
//          initial overlap. The two meshes are independent (no shared nodes)
//          and non-matching: every mesh size of the upper body is `ratio`
//          times that of the lower body. Both poles are mesh nodes.
//          Hertz (cylinders): effective radius R_l R_u / (R_l + R_u).
//
// Parameters (override with  -setnumber name value; lengths in model units):
//   level  refinement level (integer, may be negative to coarsen);
//          every mesh size below is multiplied by 2^-level          [0]
//   R_l    radius of the lower half disc                             [1]
//   R_u    radius of the upper half disc                             [1]
//   gap    height of the upper pole above the lower pole (neg. =
//          overlap)                                                  [0]
//   h_c    lower body: mesh size within distance r_c of the
//          contact point (level 0)                                   [1/40]
//   h_far  lower body: mesh size far from the contact point          [1/2]
//   ratio  upper body sizes = ratio * lower body sizes               [1.5]
//   r_c    radius of the uniformly refined contact zone              [1/4]
//   d_far  distance from the contact point where h_far is reached;
//          linear growth from h_c at r_c                             [2]
//
// Run :    gmsh -2 two_half_discs.geo -format msh41 -o two_half_discs.msh
//          gmsh -2 two_half_discs.geo -setnumber level 1 -o thd_l1.msh
//
// Physical groups (P1: 3-node triangles, 2-node lines):
//
//                          upper_support (y = R_u + gap)
//                   +---------------------------------+
//                    `.           upper             .'
//                      `-._                     _.-'  <- upper_contact
//                          `--.____________.--'          (whole arc)
//                                   o (0,gap) upper pole
//                                   o (0,0)   lower pole
//                          .--''''''''''''''--.   <- lower_contact
//                      .-'                      `-.      (whole arc)
//                    .'           lower            `.
//                   +---------------------------------+
//                          lower_support (y = -R_l)
//
// Boundary lines are oriented counter-clockwise around their body (the body
// is on the left of each line, outward normal = (dy, -dx)).
// ----------------------------------------------------------------------------

DefineConstant[
  level = {0, Name "Parameters/level"},
  R_l = {1, Name "Parameters/R_l"},
  R_u = {1, Name "Parameters/R_u"},
  gap = {0, Name "Parameters/gap"},
  h_c = {1 / 40, Name "Parameters/h_c"},
  h_far = {1 / 2, Name "Parameters/h_far"},
  ratio = {1.5, Name "Parameters/ratio"},
  r_c = {1 / 4, Name "Parameters/r_c"},
  d_far = {2, Name "Parameters/d_far"}
];

Geometry.AutoCoherence = 0; // never merge coincident points (bodies are disjoint)
s = 2 ^ (-level);           // size factor of this refinement level

// --- lower half disc: centre (0,-R_l), pole up at the origin ---------------------
p0 = newp; Point(p0) = {0, -R_l, 0};   // centre
p1 = newp; Point(p1) = {0, 0, 0};      // pole
p2 = newp; Point(p2) = {-R_l, -R_l, 0};
p3 = newp; Point(p3) = {R_l, -R_l, 0};
la1 = newl; Circle(la1) = {p3, p0, p1};
la2 = newl; Circle(la2) = {p1, p0, p2};
l_lo_chord = newl; Line(l_lo_chord) = {p2, p3};
cl = newll; Curve Loop(cl) = {la1, la2, l_lo_chord};
s_lower = news; Plane Surface(s_lower) = {cl};

// --- upper half disc: centre (0,R_u+gap), pole down at (0,gap) --------------------
yc = R_u + gap;
q0 = newp; Point(q0) = {0, yc, 0};     // centre
q1 = newp; Point(q1) = {0, gap, 0};    // pole
q2 = newp; Point(q2) = {R_u, yc, 0};
q3 = newp; Point(q3) = {-R_u, yc, 0};
ua1 = newl; Circle(ua1) = {q3, q0, q1};
ua2 = newl; Circle(ua2) = {q1, q0, q2};
l_up_chord = newl; Line(l_up_chord) = {q2, q3};
cl = newll; Curve Loop(cl) = {ua1, ua2, l_up_chord};
s_upper = news; Plane Surface(s_upper) = {cl};

// --- mesh size: refinement towards the contact point, one field per body ---------
Field[1] = Distance;
Field[1].PointsList = {p1, q1};
Field[2] = Threshold;              // lower body
Field[2].InField = 1;
Field[2].SizeMin = h_c * s;
Field[2].SizeMax = h_far * s;
Field[2].DistMin = r_c;
Field[2].DistMax = d_far;
Field[3] = Threshold;              // upper body (ratio x coarser)
Field[3].InField = 1;
Field[3].SizeMin = ratio * h_c * s;
Field[3].SizeMax = ratio * h_far * s;
Field[3].DistMin = r_c;
Field[3].DistMax = d_far;
Field[4] = Restrict;
Field[4].InField = 2;
Field[4].SurfacesList = {s_lower};
Field[4].CurvesList = {la1, la2, l_lo_chord};
Field[4].PointsList = {p1, p2, p3};
Field[5] = Restrict;
Field[5].InField = 3;
Field[5].SurfacesList = {s_upper};
Field[5].CurvesList = {ua1, ua2, l_up_chord};
Field[5].PointsList = {q1, q2, q3};
Field[6] = Min;
Field[6].FieldsList = {4, 5};
Background Field = 6;

Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.Algorithm = 6; // Frontal-Delaunay
Mesh.ElementOrder = 1;

// --- physical groups ------------------------------------------------------------
Physical Surface("lower") = {s_lower};
Physical Surface("upper") = {s_upper};
Physical Curve("lower_contact") = {la1, la2};
Physical Curve("upper_contact") = {ua1, ua2};
Physical Curve("lower_support") = {l_lo_chord};
Physical Curve("upper_support") = {l_up_chord};
