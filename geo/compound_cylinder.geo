// Compound cylinder, quarter model: an inner ring 0.5 < r < 0.75 bonded to an outer ring
// 0.75 < r < 1 along the arc r = c ("ring"), first quadrant (plane strain). The bore r = a
// carries the internal pressure, the mantle r = b the exact radial displacement, the
// straight edges lie on the symmetry axes (one Physical Curve per ring, so that a scene can
// also load them with the exact tractions instead).
// Elements per unit length on every curve:  gmsh -2 -setnumber n 32 ...
DefineConstant[
  n = {16, Name "Parameters/elements per unit length"}
];
a = 0.5; c = 0.75; b = 1;

Point(1) = {0, 0, 0};  // centre of the arcs
Point(2) = {a, 0, 0};
Point(3) = {c, 0, 0};
Point(4) = {b, 0, 0};
Point(5) = {0, b, 0};
Point(6) = {0, c, 0};
Point(7) = {0, a, 0};

Line(1) = {2, 3};        // symmetry y = 0, inner ring
Line(2) = {3, 4};        // symmetry y = 0, outer ring
Circle(3) = {4, 1, 5};   // mantle r = b
Line(4) = {5, 6};        // symmetry x = 0, outer ring
Line(5) = {6, 7};        // symmetry x = 0, inner ring
Circle(6) = {7, 1, 2};   // bore r = a
Circle(7) = {3, 1, 6};   // the bonded interface r = c

Transfinite Curve{1, 5} = Round(n * (c - a)) + 1;
Transfinite Curve{2, 4} = Round(n * (b - c)) + 1;
Transfinite Curve{3} = Round(n * Pi * b / 2) + 1;
Transfinite Curve{6} = Round(n * Pi * a / 2) + 1;
Transfinite Curve{7} = Round(n * Pi * c / 2) + 1;

Curve Loop(1) = {1, 7, 5, 6};
Curve Loop(2) = {2, 3, 4, -7};
Plane Surface(1) = {1};
Plane Surface(2) = {2};

Physical Surface("inner") = {1};
Physical Surface("outer") = {2};
Physical Curve("bore") = {6};
Physical Curve("mantle") = {3};
Physical Curve("symmetry_inner") = {1, 5};
Physical Curve("symmetry_outer") = {2, 4};
Physical Curve("ring") = {7};
