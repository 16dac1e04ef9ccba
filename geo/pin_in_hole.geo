// A pin in a hole with clearance (Persson's conforming contact), half model y >= 0: a pin of
// radius R1 = R2 - dR drawn in the hole of radius R2 of a plate (an annulus R2 < r < r_out,
// held on its outer circle), touching it at (R2, 0). The pin's centre is (dR, 0), the
// hole's (0, 0). The pin is loaded through a small hole of radius r0 at its centre (a point
// force in the limit r0 -> 0); the x axis is the symmetry plane. Each body is drawn with its
// own points and curves, so gmsh meshes the pin's circle and the hole on their own: uniform
// elements over 0 <= theta <= 100 degrees (n_pin on the pin, n_hole on the hole), coarser
// behind. Physical Curves: "pin_side" and "hole" (the two sides of the contact, for
// `between`), "load" (the small hole), "symmetry", "outer".
// Sizes are parameters:  gmsh -2 -setnumber n_pin 400 -setnumber r_out 400 ...
Geometry.AutoCoherence = 0;   // keep the coincident points of the two bodies at (R2, 0) apart
DefineConstant[
  n_pin = {400, Name "Parameters/elements on the pin's circle, 0 to 100 degrees"},
  n_hole = {360, Name "Parameters/elements on the hole, 0 to 100 degrees"},
  n_back = {40, Name "Parameters/elements on either circle, 100 to 180 degrees"},
  n_load = {32, Name "Parameters/elements on each quarter of the loaded small hole"},
  n_out = {60, Name "Parameters/elements on each quarter of the outer circle"},
  r_out = {200, Name "Parameters/outer radius of the plate"},
  dR = {0.01, Name "Parameters/radial clearance R2 - R1"},
  r0 = {0.5, Name "Parameters/radius of the loaded small hole in the pin"}
];
R2 = 10; R1 = R2 - dR;
tf = 100 * Pi / 180;                       // end of the uniform part of the circles
h_c = R2 * tf / n_hole;                    // element size at the contact
h_b = R2 * (Pi - tf) / n_back;             // behind
h_r = r_out * Pi / 2 / n_out;              // on the outer circle

// The pin: centre (dR, 0).
Point(1) = {dR, 0, 0};
Point(2) = {dR + R1, 0, 0, h_c};
Point(3) = {dR + R1 * Cos(tf), R1 * Sin(tf), 0};
Point(4) = {dR - R1, 0, 0, h_b};
Point(5) = {dR - r0, 0, 0, r0 * Pi / 2 / n_load};
Point(6) = {dR, r0, 0};
Point(7) = {dR + r0, 0, 0, r0 * Pi / 2 / n_load};
Circle(1) = {2, 1, 3};   // the pin's side, uniform
Circle(2) = {3, 1, 4};   // the pin's side, behind
Line(3) = {4, 5};        // symmetry, behind the small hole
Circle(4) = {5, 1, 6};   // the small hole (loaded)
Circle(5) = {6, 1, 7};
Line(6) = {7, 2};        // symmetry, in front of the small hole

// The plate: the hole's centre (0, 0).
Point(11) = {0, 0, 0};
Point(12) = {R2, 0, 0, h_c};
Point(13) = {r_out, 0, 0, h_r};
Point(14) = {0, r_out, 0};
Point(15) = {-r_out, 0, 0, h_r};
Point(16) = {-R2, 0, 0, h_b};
Point(17) = {R2 * Cos(tf), R2 * Sin(tf), 0};
Line(11) = {12, 13};       // symmetry, in front
Circle(12) = {13, 11, 14}; // outer circle (held)
Circle(13) = {14, 11, 15};
Line(14) = {15, 16};       // symmetry, behind
Circle(15) = {16, 11, 17}; // the hole, behind
Circle(16) = {17, 11, 12}; // the hole, uniform

Transfinite Curve{1} = Round(n_pin) + 1;
Transfinite Curve{16} = Round(n_hole) + 1;
Transfinite Curve{2, 15} = Round(n_back) + 1;
Transfinite Curve{4, 5} = Round(n_load) + 1;
Transfinite Curve{12, 13} = Round(n_out) + 1;

Curve Loop(1) = {1, 2, 3, 4, 5, 6};
Curve Loop(2) = {11, 12, 13, 14, 15, 16};
Plane Surface(1) = {1};
Plane Surface(2) = {2};

Physical Surface("pin") = {1};
Physical Surface("plate") = {2};
Physical Curve("pin_side") = {1, 2};
Physical Curve("hole") = {15, 16};
Physical Curve("load") = {4, 5};
Physical Curve("symmetry") = {3, 6, 11, 14};
Physical Curve("outer") = {12, 13};
