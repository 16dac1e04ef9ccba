// The paper's example 3: a depressed (segmental) vault on two masonry piers, under its own
// weight. Six bodies, left to right: pier_L | v1 | v2 | v3 | v4 | pier_R, joined by five
// radial joint sections s1..s5 (s1, s5 the springings on the piers, s2, s4 the haunches,
// s3 the crown), each `depth` deep and meshed with exactly n_joint elements.
//
// The paper gives the joints (50 cm, 18 nodes) and the materials but draws the rest only in
// a figure, so the span and rise are our choice: a segmental arch of span 600 cm (intrados
// chord at the springings) and rise 120 cm (rise/span 1/5), ring depth 50 cm; every joint
// is radial and the four vault bodies subtend equal angles. Each pier is a rectangle 150 cm
// wide whose top corner next to the vault is cut by the springing joint (the skewback); its
// base lies 500 cm below the intrados springing and is clamped. Of 48 geometries tried
// (span 400-1000 cm, rise/span 1/4-1/6, piers 100-150 cm wide, 250-500 cm tall) this one
// opens its joints in the paper's order: none at c = 0.4 MPa, the springings from 0.3, the
// crown from 0.1 (pipelines/vault_c*.toml).
//
// Units: cm. Sizes and dimensions are parameters:
//   gmsh -2 -setnumber h 2 -setnumber span 800 -setnumber rise 160 vault.geo
DefineConstant[
  span = {600, Name "Parameters/span at the intrados springings (cm)"},
  rise = {120, Name "Parameters/rise of the intrados (cm)"},
  depth = {50, Name "Parameters/depth of the ring and of every joint (cm)"},
  pier_w = {150, Name "Parameters/pier width (cm)"},
  pier_h = {500, Name "Parameters/pier height below the intrados springing (cm)"},
  n_joint = {17, Name "Parameters/elements on each joint"},
  h = {4, Name "Parameters/element size on the intrados and extrados (cm)"},
  h_pier = {10, Name "Parameters/element size on the piers away from the joints (cm)"}
];

R = (span^2 / 4 + rise^2) / (2 * rise);   // intrados radius
yc = rise - R;                            // centre (0, yc)
alpha = Asin(span / (2 * R));             // half opening angle
Re = R + depth;                           // extrados radius
hj = depth / n_joint;                     // joint element length

Point(1) = {0, yc, 0, hj};                // centre of both arcs
// Joint k (k = 0..4 for s1..s5) at angle th = -alpha + k alpha/2 from the vertical:
// intrados point 10 + k, extrados point 20 + k.
For k In {0:4}
  th = -alpha + k * alpha / 2;
  Point(10 + k) = {R * Sin(th), yc + R * Cos(th), 0, hj};
  Point(20 + k) = {Re * Sin(th), yc + Re * Cos(th), 0, hj};
EndFor

// Joints s1..s5: lines 1..5, intrados to extrados.
For k In {0:4}
  Line(1 + k) = {10 + k, 20 + k};
EndFor
Transfinite Curve{1:5} = n_joint + 1;

// Intrados arcs 11..14 and extrados arcs 21..24 between consecutive joints.
For k In {0:3}
  Circle(11 + k) = {10 + k, 1, 11 + k};
  Circle(21 + k) = {20 + k, 1, 21 + k};
  Transfinite Curve{11 + k} = Ceil(R * alpha / 2 / h) + 1;
  Transfinite Curve{21 + k} = Ceil(Re * alpha / 2 / h) + 1;
EndFor

// Piers: inner face at the intrados springing x = -/+ span/2, top at the extrados springing.
xi = span / 2;
ye = yc + Re * Cos(alpha);
Point(30) = {-xi - pier_w, -pier_h, 0, h_pier};   // left pier: base outer
Point(31) = {-xi, -pier_h, 0, h_pier};            // base inner
Point(32) = {-xi - pier_w, ye, 0, h_pier};        // top outer
Point(40) = {xi + pier_w, -pier_h, 0, h_pier};    // right pier
Point(41) = {xi, -pier_h, 0, h_pier};
Point(42) = {xi + pier_w, ye, 0, h_pier};

Line(31) = {30, 31};   // left base
Line(32) = {31, 10};   // left inner face, up to the intrados springing
Line(33) = {20, 32};   // left top, from the extrados springing outwards
Line(34) = {32, 30};   // left outer face
Line(41) = {41, 40};   // right base
Line(42) = {14, 41};   // right inner face, down from the intrados springing
Line(43) = {42, 24};   // right top, inwards to the extrados springing
Line(44) = {40, 42};   // right outer face

Curve Loop(1) = {31, 32, 1, 33, 34};              // pier_L
Curve Loop(2) = {1, 21, -2, -11};                 // v1
Curve Loop(3) = {2, 22, -3, -12};                 // v2
Curve Loop(4) = {3, 23, -4, -13};                 // v3
Curve Loop(5) = {4, 24, -5, -14};                 // v4
Curve Loop(6) = {41, 44, 43, -5, 42};             // pier_R
For k In {1:6}
  Plane Surface(k) = {k};
EndFor

Physical Surface("pier_L") = {1};
Physical Surface("v1") = {2};
Physical Surface("v2") = {3};
Physical Surface("v3") = {4};
Physical Surface("v4") = {5};
Physical Surface("pier_R") = {6};
Physical Curve("s1") = {1};
Physical Curve("s2") = {2};
Physical Curve("s3") = {3};
Physical Curve("s4") = {4};
Physical Curve("s5") = {5};
Physical Curve("intrados") = {11:14};
Physical Curve("extrados") = {21:24};
Physical Curve("pier_faces") = {32, 33, 34, 42, 43, 44};
Physical Curve("base") = {31, 41};
