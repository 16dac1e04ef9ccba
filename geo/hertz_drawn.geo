// Hertz line contact from the drawing, symmetric half model (x >= 0): a half cylinder of
// radius R (a quarter disc here) drawn a gap g0 above a flat block W x H. Nothing in the
// scene gives the gap: sgbem measures it from the two curves, which gmsh meshes on their
// own (non-matching nodes: elements of h_fine on the flat, 0.8 h_fine on the arc near the
// contact, graded away from it).
// Sizes are parameters:  gmsh -2 -setnumber h_fine 0.05 ...
DefineConstant[
  h_fine = {0.1, Name "Parameters/element size near the contact"},
  a_fine = {5, Name "Parameters/length of the uniform part of the contact from the axis"},
  h = {5, Name "Parameters/element size away from the contact"},
  g0 = {0.01, Name "Parameters/gap between the cylinder and the flat on the axis"}
];
R = 100; W = 100; H = 100;

// The flat block [0, W] x [-H, 0].
Point(1) = {0, 0, 0, h_fine};
Point(2) = {a_fine, 0, 0, h_fine};
Point(3) = {W, 0, 0, h};
Point(4) = {W, -H, 0, h};
Point(5) = {0, -H, 0, h};
Line(1) = {1, 2};   // contact, uniform
Line(2) = {2, 3};   // contact, graded
Line(3) = {3, 4};   // free side
Line(4) = {4, 5};   // base
Line(5) = {5, 1};   // symmetry edge

// The cylinder: centre (0, R + g0), lowest point (0, g0).
t = a_fine / R;
Point(11) = {0, g0, 0, 0.8 * h_fine};
Point(12) = {0, R + g0, 0, h};
Point(13) = {R * Sin(t), R + g0 - R * Cos(t), 0, 0.8 * h_fine};
Point(14) = {R, R + g0, 0, h};
Circle(11) = {11, 12, 13};   // contact side, uniform
Circle(12) = {13, 12, 14};   // contact side, graded
Line(13) = {14, 12};         // diametral plane (loaded)
Line(14) = {12, 11};         // symmetry edge

Transfinite Curve{1} = Round(a_fine / h_fine) + 1;
Transfinite Curve{11} = Round(a_fine / (0.8 * h_fine)) + 1;

Curve Loop(1) = {1, 2, 3, 4, 5};
Curve Loop(2) = {11, 12, 13, 14};
Plane Surface(1) = {1};
Plane Surface(2) = {2};

Physical Surface("flat") = {1};
Physical Surface("cylinder") = {2};
Physical Curve("contact") = {1, 2, 11, 12};
Physical Curve("top") = {13};
Physical Curve("base") = {4};
Physical Curve("symmetry") = {5, 14};
Physical Curve("side") = {3};
