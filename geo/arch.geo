// A parametric masonry arch of nv voussoirs on two abutments: semicircular (half_angle =
// 90) or segmental (half_angle < 90), radial joints, clamped abutment bases.
//
// Centre at the origin; the voussoirs span the angles -half_angle .. +half_angle measured
// from the vertical, all equal. Each abutment is a block whose top face IS the springing
// joint (so no point touches three bodies) and whose two other faces drop vertically from
// the joint's ends to the base, abut_h below the intrados springing.
//
// Physical groups (few, for glob and default tables in the scene):
//   Surfaces  voussoir_1 .. voussoir_<nv> (left to right), abutment_L, abutment_R
//   Curves    joints (all nv + 1 joints, springings included: split per pair of bodies by
//             sgbem), intrados, extrados, abutment_faces (free), base (to clamp)
//
// Units: any (the shipped scene uses m). E.g. 40 voussoirs, t/R = 0.1:
//   gmsh -2 -setnumber nv 40 -setnumber t 0.5 geo/arch.geo
DefineConstant[
  nv = {20, Name "Parameters/number of voussoirs (>= 2)"},
  R = {5, Name "Parameters/radius of the centre line"},
  t = {0.6, Name "Parameters/thickness of the ring (radial)"},
  half_angle = {90, Name "Parameters/half opening angle in degrees (90: semicircular)"},
  abut_h = {1, Name "Parameters/abutment height below the intrados springing"},
  nj = {6, Name "Parameters/elements on each joint"},
  h = {0, Name "Parameters/element size on intrados and extrados (0: the joint's)"}
];

If (nv < 2 || t <= 0 || t >= 2 * R || half_angle <= 0 || half_angle > 90 || nj < 1)
  Error("arch.geo: need nv >= 2, 0 < t < 2 R, 0 < half_angle <= 90, nj >= 1");
  Abort;
EndIf

Ri = R - t / 2;                   // intrados radius
Re = R + t / 2;                   // extrados radius
alpha = half_angle * Pi / 180;
hj = t / nj;                      // joint element length
hs = (h > 0) ? h : hj;            // element size along the arcs

Point(1) = {0, 0, 0, hj};
// Joint k (k = 0 .. nv) at angle th_k from the vertical: intrados point 10 + k, extrados
// point 10 + nv + 1 + k; line 10 + k from intrados to extrados.
pe = 10 + nv + 1;
For k In {0:nv}
  th = -alpha + 2 * alpha * k / nv;
  Point(10 + k) = {Ri * Sin(th), Ri * Cos(th), 0, hj};
  Point(pe + k) = {Re * Sin(th), Re * Cos(th), 0, hj};
  Line(10 + k) = {10 + k, pe + k};
  Transfinite Curve{10 + k} = nj + 1;
EndFor

// Arcs of voussoir k (k = 1 .. nv): intrados ci + k, extrados ce + k.
ci = 10 + 2 * (nv + 1);
ce = ci + nv;
For k In {1:nv}
  Circle(ci + k) = {10 + k - 1, 1, 10 + k};
  Circle(ce + k) = {pe + k - 1, 1, pe + k};
  Transfinite Curve{ci + k} = Ceil(Ri * 2 * alpha / nv / hs) + 1;
  Transfinite Curve{ce + k} = Ceil(Re * 2 * alpha / nv / hs) + 1;
  Curve Loop(k) = {ci + k, 10 + k, -(ce + k), -(10 + k - 1)};
  Plane Surface(k) = {k};
  Physical Surface(Sprintf("voussoir_%g", k)) = {k};
EndFor

// Abutments: vertical faces from the springing joint's ends down to the base.
yb = Ri * Cos(alpha) - abut_h;
ab = ce + nv + 1;                 // first free tag
hb = (abut_h > hj) ? abut_h / Ceil(abut_h / hs) : hj;
Point(ab) = {-Ri * Sin(alpha), yb, 0, hb};      // left: below the intrados end
Point(ab + 1) = {-Re * Sin(alpha), yb, 0, hb};  // left: below the extrados end
Point(ab + 2) = {Ri * Sin(alpha), yb, 0, hb};   // right
Point(ab + 3) = {Re * Sin(alpha), yb, 0, hb};
Line(ab) = {10, ab};                 // left inner face, down
Line(ab + 1) = {ab, ab + 1};         // left base
Line(ab + 2) = {ab + 1, pe};         // left outer face, up
Line(ab + 3) = {10 + nv, ab + 2};    // right inner face, down
Line(ab + 4) = {ab + 2, ab + 3};     // right base
Line(ab + 5) = {ab + 3, pe + nv};    // right outer face, up
Transfinite Curve{ab + 1, ab + 4} = nj + 1;
Curve Loop(nv + 1) = {10, -(ab + 2), -(ab + 1), -ab};
Curve Loop(nv + 2) = {10 + nv, -(ab + 5), -(ab + 4), -(ab + 3)};
Plane Surface(nv + 1) = {nv + 1};
Plane Surface(nv + 2) = {nv + 2};
Physical Surface("abutment_L") = {nv + 1};
Physical Surface("abutment_R") = {nv + 2};

Physical Curve("joints") = {10:10 + nv};
Physical Curve("intrados") = {ci + 1:ci + nv};
Physical Curve("extrados") = {ce + 1:ce + nv};
Physical Curve("abutment_faces") = {ab, ab + 2, ab + 3, ab + 5};
Physical Curve("base") = {ab + 1, ab + 4};
