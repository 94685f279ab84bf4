// ----------------------------------------------------------------------------
// two_hemispheres.geo -- internodes mesh: 3D Hertz contact between two
//                        elastic hemispheres, pole against pole
// ----------------------------------------------------------------------------
//
// Models : lower body = upper half of the sphere of radius R_l centred at
//          (0,0,-R_l): pole up at the origin, flat face at z = -R_l.
//          upper body = lower half of the sphere of radius R_u centred at
//          (0,0,R_u+gap): pole down at (0,0,gap), flat face at z = R_u + gap.
//          With gap = 0 the two bodies touch at the origin only; gap < 0 is an
//          initial overlap. The two meshes are independent (no shared nodes)
//          and non-matching: every mesh size of the upper body is `ratio`
//          times that of the lower body. Both poles are mesh nodes.
//          Hertz: effective radius R_l R_u / (R_l + R_u), a ~ 0.1 R.
//
// Parameters (override with  -setnumber name value; lengths in model units):
//   level  refinement level (integer, may be negative to coarsen);
//          every mesh size below is multiplied by 2^-level          [0]
//   R_l    radius of the lower hemisphere                            [1]
//   R_u    radius of the upper hemisphere                            [1]
//   gap    height of the upper pole above the lower pole (neg. =
//          overlap)                                                  [0]
//   h_c    lower body: mesh size within distance r_c of the
//          contact point (level 0)                                   [1/15]
//   h_far  lower body: mesh size far from the contact point          [1/2]
//   ratio  upper body sizes = ratio * lower body sizes               [1.5]
//   r_c    radius of the uniformly refined contact zone              [1/4]
//   d_far  distance from the contact point where h_far is
//          reached; linear growth from h_c at r_c                    [2]
//
// Run :    gmsh -3 two_hemispheres.geo -format msh41 -o two_hemispheres.msh
//          gmsh -3 two_hemispheres.geo -setnumber level 1 -o th_l1.msh
//
// Physical groups (P1: 4-node tetrahedra, 3-node triangles), section y = 0:
//
//                      upper_support (z = R_u + gap, flat disc)
//                 +---------------------------------+
//                  `.          upper              .'
//                     `-.     (volume)        .-'  <- upper_contact
//                        `--._________.--'            (whole curved surface)
//                                 o  (0,0,gap) upper pole
//                                 o  (0,0,0)   lower pole
//                        .--'''''''''''''--.   <- lower_contact
//                     .-'                   `-.       (whole curved surface)
//                  .'          lower            `.
//                 /           (volume)            \
//                +---------------------------------+
//                      lower_support (z = -R_l, flat disc)
//
// Boundary triangles are oriented with their right-hand normal pointing out
// of their body.
// ----------------------------------------------------------------------------

DefineConstant[
  level = {0, Name "Parameters/level"},
  R_l = {1, Name "Parameters/R_l"},
  R_u = {1, Name "Parameters/R_u"},
  gap = {0, Name "Parameters/gap"},
  h_c = {1 / 15, Name "Parameters/h_c"},
  h_far = {1 / 2, Name "Parameters/h_far"},
  ratio = {1.5, Name "Parameters/ratio"},
  r_c = {1 / 4, Name "Parameters/r_c"},
  d_far = {2, Name "Parameters/d_far"}
];

Geometry.AutoCoherence = 0; // never merge coincident points (bodies are disjoint)
s = 2 ^ (-level);           // size factor of this refinement level

// --- hemisphere macro -------------------------------------------------------------
// input : hs_zp (pole height), hs_R (radius), hs_sgn (+1: pole down, flat face
//         on top; -1: pole up, flat face at the bottom), hs_th (polar angle of
//         the internal latitude split, radians)
// output: hs_pole, hs_vol, hs_curved[] (curved surface), hs_flat (flat face),
//         hs_surfs[], hs_curves[], hs_points[] (all entities, for Restrict)
Macro Hemisphere
  hs_zc = hs_zp + hs_sgn * hs_R;                  // centre / flat face height
  hs_zl = hs_zc - hs_sgn * hs_R * Cos(hs_th);     // latitude circle height
  hs_pC = newp; Point(hs_pC) = {0, 0, hs_zc};
  hs_pole = newp; Point(hs_pole) = {0, 0, hs_zp};
  hs_pL = newp; Point(hs_pL) = {0, 0, hs_zl};
  hs_points[] = {hs_pole};
  For hs_i In {0:3}
    hs_L[hs_i] = newp;
    Point(hs_L[hs_i]) = {hs_R * Sin(hs_th) * Cos(hs_i * Pi / 2), hs_R * Sin(hs_th) * Sin(hs_i * Pi / 2), hs_zl};
    hs_E[hs_i] = newp;
    Point(hs_E[hs_i]) = {hs_R * Cos(hs_i * Pi / 2), hs_R * Sin(hs_i * Pi / 2), hs_zc};
    hs_points[] += {hs_L[hs_i], hs_E[hs_i]};
  EndFor
  hs_curves[] = {};
  For hs_i In {0:3}
    hs_j = (hs_i + 1) % 4;
    hs_lat[hs_i] = newl; Circle(hs_lat[hs_i]) = {hs_L[hs_i], hs_pL, hs_L[hs_j]};
    hs_eq[hs_i] = newl; Circle(hs_eq[hs_i]) = {hs_E[hs_i], hs_pC, hs_E[hs_j]};
    hs_mer[hs_i] = newl; Circle(hs_mer[hs_i]) = {hs_L[hs_i], hs_pC, hs_E[hs_i]};
    hs_pm[hs_i] = newl; Circle(hs_pm[hs_i]) = {hs_pole, hs_pC, hs_L[hs_i]};
    hs_curves[] += {hs_lat[hs_i], hs_eq[hs_i], hs_mer[hs_i], hs_pm[hs_i]};
  EndFor
  // loops are counter-clockwise seen from outside (outward right-hand normal)
  hs_curved[] = {};
  For hs_i In {0:3}
    hs_j = (hs_i + 1) % 4;
    hs_cl = newll;
    If (hs_sgn > 0)
      Curve Loop(hs_cl) = {hs_pm[hs_j], -hs_lat[hs_i], -hs_pm[hs_i]};
    Else
      Curve Loop(hs_cl) = {hs_pm[hs_i], hs_lat[hs_i], -hs_pm[hs_j]};
    EndIf
    hs_s = news; Surface(hs_s) = {hs_cl} In Sphere {hs_pC};
    hs_curved[] += {hs_s};
    hs_cl = newll;
    If (hs_sgn > 0)
      Curve Loop(hs_cl) = {hs_lat[hs_i], hs_mer[hs_j], -hs_eq[hs_i], -hs_mer[hs_i]};
    Else
      Curve Loop(hs_cl) = {hs_mer[hs_i], hs_eq[hs_i], -hs_mer[hs_j], -hs_lat[hs_i]};
    EndIf
    hs_s = news; Surface(hs_s) = {hs_cl} In Sphere {hs_pC};
    hs_curved[] += {hs_s};
  EndFor
  hs_cl = newll;
  If (hs_sgn > 0)
    Curve Loop(hs_cl) = {hs_eq[0], hs_eq[1], hs_eq[2], hs_eq[3]};
  Else
    Curve Loop(hs_cl) = {-hs_eq[3], -hs_eq[2], -hs_eq[1], -hs_eq[0]};
  EndIf
  hs_flat = news; Plane Surface(hs_flat) = {hs_cl};
  hs_surfs[] = {hs_curved[], hs_flat};
  hs_sl = newsl; Surface Loop(hs_sl) = {hs_surfs[]};
  hs_vol = newv; Volume(hs_vol) = {hs_sl};
Return

// --- lower hemisphere: pole up at the origin -------------------------------------
hs_zp = 0; hs_R = R_l; hs_sgn = -1; hs_th = Pi / 4;
Call Hemisphere;
lo_pole = hs_pole; lo_vol = hs_vol; lo_curved[] = hs_curved[]; lo_flat = hs_flat;
lo_surfs[] = hs_surfs[]; lo_curves[] = hs_curves[]; lo_points[] = hs_points[];

// --- upper hemisphere: pole down at (0,0,gap) -------------------------------------
hs_zp = gap; hs_R = R_u; hs_sgn = 1; hs_th = Pi / 4;
Call Hemisphere;
up_pole = hs_pole; up_vol = hs_vol; up_curved[] = hs_curved[]; up_flat = hs_flat;
up_surfs[] = hs_surfs[]; up_curves[] = hs_curves[]; up_points[] = hs_points[];

// --- mesh size: refinement towards the contact point, one field per body ---------
Field[1] = Distance;
Field[1].PointsList = {lo_pole, up_pole};
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
Field[4].VolumesList = {lo_vol};
Field[4].SurfacesList = {lo_surfs[]};
Field[4].CurvesList = {lo_curves[]};
Field[4].PointsList = {lo_points[]};
Field[5] = Restrict;
Field[5].InField = 3;
Field[5].VolumesList = {up_vol};
Field[5].SurfacesList = {up_surfs[]};
Field[5].CurvesList = {up_curves[]};
Field[5].PointsList = {up_points[]};
Field[6] = Min;
Field[6].FieldsList = {4, 5};
Background Field = 6;

Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.Algorithm = 6;   // Frontal-Delaunay (surfaces)
Mesh.Algorithm3D = 1; // Delaunay
Mesh.ElementOrder = 1;

// --- physical groups ---------------------------------------------------------------
Physical Volume("lower") = {lo_vol};
Physical Volume("upper") = {up_vol};
Physical Surface("lower_contact") = {lo_curved[]};
Physical Surface("upper_contact") = {up_curved[]};
Physical Surface("lower_support") = {lo_flat};
Physical Surface("upper_support") = {up_flat};
