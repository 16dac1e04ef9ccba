// Timoshenko-Goodier cantilever: the beam [0, 1] x [-0.1, 0.1] (length L = 1, depth
// 2c = 0.2), loaded by a parabolic shear on its free end x = 0 and held by the exact
// displacements on x = L.
// Elements per unit length on every side:  gmsh -2 -setnumber n 40 ...
DefineConstant[
  n = {20, Name "Parameters/elements per unit length"}
];
L = 1; c = 0.1;

Point(1) = {0, -c, 0};
Point(2) = {L, -c, 0};
Point(3) = {L, c, 0};
Point(4) = {0, c, 0};

Line(1) = {1, 2};  // bottom y = -c
Line(2) = {2, 3};  // held end x = L
Line(3) = {3, 4};  // top y = c
Line(4) = {4, 1};  // loaded end x = 0

Transfinite Curve{1, 3} = Round(n * L) + 1;
Transfinite Curve{2, 4} = Round(n * 2 * c) + 1;

Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};

Physical Surface("beam") = {1};
Physical Curve("load") = {4};
Physical Curve("support") = {2};
Physical Curve("top") = {3};
Physical Curve("bottom") = {1};
