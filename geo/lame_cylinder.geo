// Lamé thick cylinder, quarter model: the ring 0.5 < r < 1 in the first quadrant (plane
// strain). The bore r = a carries the internal pressure, the mantle r = b the exact radial
// displacement, and the two straight edges lie on the symmetry axes.
// Elements per unit length on every curve:  gmsh -2 -setnumber n 32 ...
DefineConstant[
  n = {16, Name "Parameters/elements per unit length"}
];
a = 0.5; b = 1;

Point(1) = {0, 0, 0};  // centre of the arcs
Point(2) = {a, 0, 0};
Point(3) = {b, 0, 0};
Point(4) = {0, b, 0};
Point(5) = {0, a, 0};

Line(1) = {2, 3};        // symmetry on y = 0
Circle(2) = {3, 1, 4};   // mantle r = b
Line(3) = {4, 5};        // symmetry on x = 0
Circle(4) = {5, 1, 2};   // bore r = a

Transfinite Curve{1, 3} = Round(n * (b - a)) + 1;
Transfinite Curve{2} = Round(n * Pi * b / 2) + 1;
Transfinite Curve{4} = Round(n * Pi * a / 2) + 1;

Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};

Physical Surface("cylinder") = {1};
Physical Curve("bore") = {4};
Physical Curve("mantle") = {2};
Physical Curve("symmetry") = {1, 3};
