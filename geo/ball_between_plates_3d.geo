// ----------------------------------------------------------------------------
// ball_between_plates_3d.geo -- internodes mesh: a ball between two plates, 3D,
//                               a quarter model (x >= 0, y >= 0)
// ----------------------------------------------------------------------------
//
// Models : the quarter of the ball of radius R centred at the origin with
//          x >= 0 and y >= 0, between a lower plate [0,W]^2 x [-R-T,-R] and
//          an upper plate [0,W]^2 x [R,R+T] that touch its poles (0,0,-R) and
//          (0,0,R) (gap 0). The planes x = 0 and y = 0 are planes of symmetry:
//          rollers on them remove every rigid motion of the ball but the
//          vertical translation, which only its two contacts hold. The three
//          bodies are disjoint (no shared points, no shared nodes); each is
//          refined towards the poles: size h_c within r_c of a pole, growing
//          linearly to h_far at distance d_far.
//
// Parameters (-setnumber name value):
//   level  refinement level; every mesh size is multiplied by 2^-level   [0]
//   R      radius of the ball                                            [1]
//   W, T   width and thickness of the plates                             [1.5 R, R]
//   h_c, r_c, h_far, d_far   as above                       [R/15, R/4, R/3, R]
//   plate_ratio  plate sizes = plate_ratio * ball sizes                  [1.25]
//
// Physical groups: volumes ball, lower, upper; surfaces ball_lower_contact
// (z <= 0 octant of the sphere), ball_upper_contact (z >= 0), ball_sym_x
// (x = 0), ball_sym_y (y = 0); lower_contact (z = -R), lower_base, lower_sym_x,
// lower_sym_y, lower_outer (x = W and y = W); upper_contact (z = R), upper_top,
// upper_sym_x, upper_sym_y, upper_outer.
// ----------------------------------------------------------------------------

DefineConstant[
  level = {0, Name "Parameters/level"},
  R = {1, Name "Parameters/R"},
  W = {1.5 * R, Name "Parameters/W"},
  T = {R, Name "Parameters/T"},
  h_c = {R / 15, Name "Parameters/h_c"},
  r_c = {R / 4, Name "Parameters/r_c"},
  h_far = {R / 3, Name "Parameters/h_far"},
  d_far = {R, Name "Parameters/d_far"},
  plate_ratio = {1.25, Name "Parameters/plate_ratio"}
];

Geometry.AutoCoherence = 0; // never merge coincident points (bodies are disjoint)
s = 2 ^ (-level);

// --- the quarter ball -----------------------------------------------------------
pC = newp; Point(pC) = {0, 0, 0};
pT = newp; Point(pT) = {0, 0, R};
pB = newp; Point(pB) = {0, 0, -R};
pX = newp; Point(pX) = {R, 0, 0};
pY = newp; Point(pY) = {0, R, 0};
eq = newl; Circle(eq) = {pX, pC, pY};
tx = newl; Circle(tx) = {pT, pC, pX};
ty = newl; Circle(ty) = {pT, pC, pY};
bx = newl; Circle(bx) = {pB, pC, pX};
by = newl; Circle(by) = {pB, pC, pY};
axis = newl; Line(axis) = {pB, pT};
cl = newll; Curve Loop(cl) = {tx, eq, -ty};
s_up = news; Surface(s_up) = {cl} In Sphere {pC};
cl = newll; Curve Loop(cl) = {by, -eq, -bx};
s_down = news; Surface(s_down) = {cl} In Sphere {pC};
cl = newll; Curve Loop(cl) = {axis, tx, -bx};
s_symy = news; Plane Surface(s_symy) = {cl};
cl = newll; Curve Loop(cl) = {-axis, by, -ty};
s_symx = news; Plane Surface(s_symx) = {cl};
sl = newsl; Surface Loop(sl) = {s_up, s_down, s_symy, s_symx};
v_ball = newv; Volume(v_ball) = {sl};

// --- a plate [0,W]^2 x [z0, z0 + T]: its volume and faces, the pole at its corner (0,0,zp)
Macro Plate
  q1 = newp; Point(q1) = {0, 0, z0};
  q2 = newp; Point(q2) = {W, 0, z0};
  q3 = newp; Point(q3) = {W, W, z0};
  q4 = newp; Point(q4) = {0, W, z0};
  q5 = newp; Point(q5) = {0, 0, z0 + T};
  q6 = newp; Point(q6) = {W, 0, z0 + T};
  q7 = newp; Point(q7) = {W, W, z0 + T};
  q8 = newp; Point(q8) = {0, W, z0 + T};
  m1 = newl; Line(m1) = {q1, q2};
  m2 = newl; Line(m2) = {q2, q3};
  m3 = newl; Line(m3) = {q3, q4};
  m4 = newl; Line(m4) = {q4, q1};
  m5 = newl; Line(m5) = {q5, q6};
  m6 = newl; Line(m6) = {q6, q7};
  m7 = newl; Line(m7) = {q7, q8};
  m8 = newl; Line(m8) = {q8, q5};
  m9 = newl; Line(m9) = {q1, q5};
  m10 = newl; Line(m10) = {q2, q6};
  m11 = newl; Line(m11) = {q3, q7};
  m12 = newl; Line(m12) = {q4, q8};
  cl = newll; Curve Loop(cl) = {-m4, -m3, -m2, -m1};
  f_bottom = news; Plane Surface(f_bottom) = {cl};
  cl = newll; Curve Loop(cl) = {m5, m6, m7, m8};
  f_top = news; Plane Surface(f_top) = {cl};
  cl = newll; Curve Loop(cl) = {m1, m10, -m5, -m9};
  f_symy = news; Plane Surface(f_symy) = {cl};
  cl = newll; Curve Loop(cl) = {m2, m11, -m6, -m10};
  f_outx = news; Plane Surface(f_outx) = {cl};
  cl = newll; Curve Loop(cl) = {m3, m12, -m7, -m11};
  f_outy = news; Plane Surface(f_outy) = {cl};
  cl = newll; Curve Loop(cl) = {m4, m9, -m8, -m12};
  f_symx = news; Plane Surface(f_symx) = {cl};
  sl = newsl; Surface Loop(sl) = {f_bottom, f_top, f_symy, f_outx, f_outy, f_symx};
  v_plate = newv; Volume(v_plate) = {sl};
  plate_surfaces[] += {f_bottom, f_top, f_symy, f_outx, f_outy, f_symx};
  plate_curves[] += {m1, m2, m3, m4, m5, m6, m7, m8, m9, m10, m11, m12};
  plate_points[] += {q1, q2, q3, q4, q5, q6, q7, q8};
Return

plate_surfaces[] = {};
plate_curves[] = {};
plate_points[] = {};

z0 = -R - T; Call Plate;
v_lower = v_plate; lower_pole = q5;
Physical Volume("lower") = {v_lower};
Physical Surface("lower_contact") = {f_top};
Physical Surface("lower_base") = {f_bottom};
Physical Surface("lower_sym_x") = {f_symx};
Physical Surface("lower_sym_y") = {f_symy};
Physical Surface("lower_outer") = {f_outx, f_outy};

z0 = R; Call Plate;
v_upper = v_plate; upper_pole = q1;
Physical Volume("upper") = {v_upper};
Physical Surface("upper_contact") = {f_bottom};
Physical Surface("upper_top") = {f_top};
Physical Surface("upper_sym_x") = {f_symx};
Physical Surface("upper_sym_y") = {f_symy};
Physical Surface("upper_outer") = {f_outx, f_outy};

Physical Volume("ball") = {v_ball};
Physical Surface("ball_upper_contact") = {s_up};
Physical Surface("ball_lower_contact") = {s_down};
Physical Surface("ball_sym_x") = {s_symx};
Physical Surface("ball_sym_y") = {s_symy};

// --- mesh size: towards the two poles, each body with its own sizes -----------------
Field[1] = Distance;
Field[1].PointsList = {pT, pB, lower_pole, upper_pole};
Field[2] = Threshold;
Field[2].InField = 1;
Field[2].SizeMin = h_c * s;
Field[2].SizeMax = h_far * s;
Field[2].DistMin = r_c;
Field[2].DistMax = d_far;
Field[3] = Threshold;
Field[3].InField = 1;
Field[3].SizeMin = plate_ratio * h_c * s;
Field[3].SizeMax = plate_ratio * h_far * s;
Field[3].DistMin = r_c;
Field[3].DistMax = d_far;
Field[4] = Restrict;
Field[4].InField = 2;
Field[4].VolumesList = {v_ball};
Field[4].SurfacesList = {s_up, s_down, s_symx, s_symy};
Field[4].CurvesList = {eq, tx, ty, bx, by, axis};
Field[4].PointsList = {pT, pB, pX, pY};
Field[5] = Restrict;
Field[5].InField = 3;
Field[5].VolumesList = {v_lower, v_upper};
Field[5].SurfacesList = {plate_surfaces[]};
Field[5].CurvesList = {plate_curves[]};
Field[5].PointsList = {plate_points[]};
Field[6] = Min;
Field[6].FieldsList = {4, 5};
Background Field = 6;

Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.Algorithm = 6;
Mesh.Algorithm3D = 1;
Mesh.ElementOrder = 1;
