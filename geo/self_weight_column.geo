// A column [-0.25, 0.25] x [0, 1] under its own weight (plane strain): the base y = 0
// carries the exact displacements of the field sigma_yy = gamma (y - H), the sides and the
// top are traction-free.
// Elements per unit length on every side:  gmsh -2 -setnumber n 32 ...
DefineConstant[
  n = {16, Name "Parameters/elements per unit length"}
];
w = 0.5; H = 1;

Point(1) = {-w / 2, 0, 0};
Point(2) = {w / 2, 0, 0};
Point(3) = {w / 2, H, 0};
Point(4) = {-w / 2, H, 0};

Line(1) = {1, 2};  // base
Line(2) = {2, 3};  // right side
Line(3) = {3, 4};  // top
Line(4) = {4, 1};  // left side

Transfinite Curve{1, 3} = Round(n * w) + 1;
Transfinite Curve{2, 4} = Round(n * H) + 1;

Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};

Physical Surface("column") = {1};
Physical Curve("base") = {1};
Physical Curve("sides") = {2, 4};
Physical Curve("top") = {3};
