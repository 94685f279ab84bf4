// ----------------------------------------------------------------------------
// flat_blocks_3d.geo -- internodes mesh: two flat blocks pressed together, 3D,
//                       non-matching meshes; or their union
// ----------------------------------------------------------------------------
//
// Models : lower block [-W_l, W_l]^2 x [-H_l, 0] and upper block
//          [-W_u, W_u]^2 x [gap, gap + H_u], centred on the same vertical axis
//          (the z axis). gap = 0: the flat faces touch on z = 0; gap < 0: the
//          upper block is meshed -gap into the lower one. Uniform
//          (unstructured) mesh sizes h_l and h_u, so the two faces do not
//          match. The bodies are disjoint meshes (no shared nodes). Two points
//          of the lower base and two of the upper top are mesh nodes, named,
//          to pin the blocks against the horizontal rigid motions when their
//          ends slide freely: the face centre (`*_pin`: ux = uy = 0) and the
//          point half-way to the side x = +W on the axis y = 0 (`*_pin_axis`:
//          uy = 0 stops the rotation about z; y = 0 is a symmetry plane).
//          union = 1: the same two boxes (W_u = W_l, gap = 0 required) meshed
//          as ONE body `union` with a conforming interface z = 0 (the
//          reference for the symmetric set-ups: total height H_l + H_u).
//
// Parameters (override with  -setnumber name value; lengths in model units):
//   level  refinement level (integer, may be negative to coarsen);
//          every mesh size below is multiplied by 2^-level          [0]
//   W_l    half-width of the lower block (x and y)                   [0.5]
//   W_u    half-width of the upper block                            [W_l]
//   H_l    height of the lower block                                [0.5]
//   H_u    height of the upper block                                [0.5]
//   gap    height of the upper block's face above z = 0 (neg.:
//          meshed overlapping)                                      [0]
//   h_l    mesh size of the lower block (level 0)                    [1/10]
//   h_u    mesh size of the upper block (level 0)                    [h_l]
//   union  1: one body `union`, conforming interface                [0]
//
// Run :    gmsh -3 flat_blocks_3d.geo -format msh41 -o fb3.msh
//          gmsh -3 flat_blocks_3d.geo -setnumber h_u 0.05 -setnumber W_u 0.3 -o fb3n.msh
//          gmsh -3 flat_blocks_3d.geo -setnumber union 1 -setnumber h_l 0.05 -o fb3u.msh
//
// Physical groups (P1: 4-node tetrahedra, 3-node triangles), section y = 0:
//
//                                 upper_top (z = gap + H_u)
//               (-W_u,.) +-------------o------o------+ (W_u,.)
//                        |     upper_pin  upper_pin_axis
//          upper_sides   |           upper           |  upper_sides
//                        |                           |
//             (-W_u,gap) +---------------------------+ (W_u,gap) <- upper_contact
//   (-W_l,0) +-----------------------------------------------+ (W_l,0) <- lower_contact
//            |                                               |
//  lower_    |                     lower                     | lower_
//  sides     |                                               | sides
//            |          lower_pin        lower_pin_axis       |
//  (-W_l,-H_l)+----------------------o-----------o------------+ (W_l,-H_l)
//                               lower_base
//
//   *_sides are the four lateral faces of a block; *_sides_x the two faces
//   x = +-W, *_sides_y the two faces y = +-W (for rollers).
//   union = 1: Physical Volume "union" (both boxes, one body), Physical
//   Surface "interface" (z = 0), and the base, top, sides and pin groups as
//   above (no lower/upper bodies, no *_contact groups).
//
// Boundary triangles are oriented with their right-hand normal pointing out
// of their body.
// ----------------------------------------------------------------------------

DefineConstant[
  level = {0, Name "Parameters/level"},
  W_l = {0.5, Name "Parameters/W_l"},
  W_u = {W_l, Name "Parameters/W_u"},
  H_l = {0.5, Name "Parameters/H_l"},
  H_u = {0.5, Name "Parameters/H_u"},
  gap = {0, Name "Parameters/gap"},
  h_l = {1 / 10, Name "Parameters/h_l"},
  h_u = {h_l, Name "Parameters/h_u"},
  union = {0, Name "Parameters/union"}
];

If (union && (W_u != W_l || gap != 0))
  Error("flat_blocks_3d.geo: union = 1 needs W_u = W_l and gap = 0");
  Abort;
EndIf

Geometry.AutoCoherence = 0; // never merge coincident points (bodies are disjoint)
s = 2 ^ (-level);           // size factor of this refinement level
sl = h_l * s;
su = h_u * s;

// --- lower block [-W_l, W_l]^2 x [-H_l, 0] -------------------------------------------
b1 = newp; Point(b1) = {-W_l, -W_l, -H_l, sl};
b2 = newp; Point(b2) = {W_l, -W_l, -H_l, sl};
b3 = newp; Point(b3) = {W_l, W_l, -H_l, sl};
b4 = newp; Point(b4) = {-W_l, W_l, -H_l, sl};
t1 = newp; Point(t1) = {-W_l, -W_l, 0, sl};
t2 = newp; Point(t2) = {W_l, -W_l, 0, sl};
t3 = newp; Point(t3) = {W_l, W_l, 0, sl};
t4 = newp; Point(t4) = {-W_l, W_l, 0, sl};
lb1 = newl; Line(lb1) = {b1, b2};
lb2 = newl; Line(lb2) = {b2, b3};
lb3 = newl; Line(lb3) = {b3, b4};
lb4 = newl; Line(lb4) = {b4, b1};
lt1 = newl; Line(lt1) = {t1, t2};
lt2 = newl; Line(lt2) = {t2, t3};
lt3 = newl; Line(lt3) = {t3, t4};
lt4 = newl; Line(lt4) = {t4, t1};
lv1 = newl; Line(lv1) = {b1, t1};
lv2 = newl; Line(lv2) = {b2, t2};
lv3 = newl; Line(lv3) = {b3, t3};
lv4 = newl; Line(lv4) = {b4, t4};
// loops counter-clockwise seen from outside (outward right-hand normal)
cl = newll; Curve Loop(cl) = {-lb4, -lb3, -lb2, -lb1};
lo_base = news; Plane Surface(lo_base) = {cl};
cl = newll; Curve Loop(cl) = {lt1, lt2, lt3, lt4};
lo_top = news; Plane Surface(lo_top) = {cl};
cl = newll; Curve Loop(cl) = {lb1, lv2, -lt1, -lv1};
lo_sy[0] = news; Plane Surface(lo_sy[0]) = {cl};   // y = -W_l
cl = newll; Curve Loop(cl) = {lb2, lv3, -lt2, -lv2};
lo_sx[0] = news; Plane Surface(lo_sx[0]) = {cl};   // x = +W_l
cl = newll; Curve Loop(cl) = {lb3, lv4, -lt3, -lv3};
lo_sy[1] = news; Plane Surface(lo_sy[1]) = {cl};   // y = +W_l
cl = newll; Curve Loop(cl) = {lb4, lv1, -lt4, -lv4};
lo_sx[1] = news; Plane Surface(lo_sx[1]) = {cl};   // x = -W_l
sloop = newsl; Surface Loop(sloop) = {lo_base, lo_top, lo_sx[], lo_sy[]};
lo_vol = newv; Volume(lo_vol) = {sloop};
lo_pin = newp; Point(lo_pin) = {0, 0, -H_l, sl};
lo_pin_axis = newp; Point(lo_pin_axis) = {W_l / 2, 0, -H_l, sl};
Point{lo_pin, lo_pin_axis} In Surface{lo_base};

// --- upper block [-W_u, W_u]^2 x [gap, gap + H_u] ------------------------------------
zt = gap + H_u;
If (union)
  // the same box sharing the lower block's top face: one conforming mesh
  c1 = t1; c2 = t2; c3 = t3; c4 = t4;
  lc1 = lt1; lc2 = lt2; lc3 = lt3; lc4 = lt4;
  up_contact = lo_top;
Else
  c1 = newp; Point(c1) = {-W_u, -W_u, gap, su};
  c2 = newp; Point(c2) = {W_u, -W_u, gap, su};
  c3 = newp; Point(c3) = {W_u, W_u, gap, su};
  c4 = newp; Point(c4) = {-W_u, W_u, gap, su};
  lc1 = newl; Line(lc1) = {c1, c2};
  lc2 = newl; Line(lc2) = {c2, c3};
  lc3 = newl; Line(lc3) = {c3, c4};
  lc4 = newl; Line(lc4) = {c4, c1};
  cl = newll; Curve Loop(cl) = {-lc4, -lc3, -lc2, -lc1};
  up_contact = news; Plane Surface(up_contact) = {cl};
EndIf
d1 = newp; Point(d1) = {-W_u, -W_u, zt, su};
d2 = newp; Point(d2) = {W_u, -W_u, zt, su};
d3 = newp; Point(d3) = {W_u, W_u, zt, su};
d4 = newp; Point(d4) = {-W_u, W_u, zt, su};
ld1 = newl; Line(ld1) = {d1, d2};
ld2 = newl; Line(ld2) = {d2, d3};
ld3 = newl; Line(ld3) = {d3, d4};
ld4 = newl; Line(ld4) = {d4, d1};
lw1 = newl; Line(lw1) = {c1, d1};
lw2 = newl; Line(lw2) = {c2, d2};
lw3 = newl; Line(lw3) = {c3, d3};
lw4 = newl; Line(lw4) = {c4, d4};
cl = newll; Curve Loop(cl) = {ld1, ld2, ld3, ld4};
up_top = news; Plane Surface(up_top) = {cl};
cl = newll; Curve Loop(cl) = {lc1, lw2, -ld1, -lw1};
up_sy[0] = news; Plane Surface(up_sy[0]) = {cl};
cl = newll; Curve Loop(cl) = {lc2, lw3, -ld2, -lw2};
up_sx[0] = news; Plane Surface(up_sx[0]) = {cl};
cl = newll; Curve Loop(cl) = {lc3, lw4, -ld3, -lw3};
up_sy[1] = news; Plane Surface(up_sy[1]) = {cl};
cl = newll; Curve Loop(cl) = {lc4, lw1, -ld4, -lw4};
up_sx[1] = news; Plane Surface(up_sx[1]) = {cl};
sloop = newsl; Surface Loop(sloop) = {up_contact, up_top, up_sx[], up_sy[]};
up_vol = newv; Volume(up_vol) = {sloop};
up_pin = newp; Point(up_pin) = {0, 0, zt, su};
up_pin_axis = newp; Point(up_pin_axis) = {W_u / 2, 0, zt, su};
Point{up_pin, up_pin_axis} In Surface{up_top};

// --- mesh size: uniform per body (from the point sizes) ----------------------------
Mesh.MeshSizeFromPoints = 1;
Mesh.MeshSizeFromCurvature = 0;
Mesh.MeshSizeExtendFromBoundary = 1;
Mesh.Algorithm = 6;   // Frontal-Delaunay (surfaces)
Mesh.Algorithm3D = 1; // Delaunay
Mesh.ElementOrder = 1;

// --- physical groups ------------------------------------------------------------
If (union)
  Physical Volume("union") = {lo_vol, up_vol};
  Physical Surface("interface") = {lo_top};
Else
  Physical Volume("lower") = {lo_vol};
  Physical Volume("upper") = {up_vol};
  Physical Surface("lower_contact") = {lo_top};
  Physical Surface("upper_contact") = {up_contact};
EndIf
Physical Surface("lower_base") = {lo_base};
Physical Surface("upper_top") = {up_top};
Physical Surface("lower_sides") = {lo_sx[], lo_sy[]};
Physical Surface("upper_sides") = {up_sx[], up_sy[]};
Physical Surface("lower_sides_x") = {lo_sx[]};
Physical Surface("lower_sides_y") = {lo_sy[]};
Physical Surface("upper_sides_x") = {up_sx[]};
Physical Surface("upper_sides_y") = {up_sy[]};
Physical Point("lower_pin") = {lo_pin};
Physical Point("lower_pin_axis") = {lo_pin_axis};
Physical Point("upper_pin") = {up_pin};
Physical Point("upper_pin_axis") = {up_pin_axis};
