// Two stacked blocks: "lower" [0,1] x [0,0.5] on a clamped base, "upper" [0,1] x [0.5,1]
// on top of it, joined along y = 0.5 by the curve "joint".
// Elements per unit length:  gmsh -2 -setnumber n 16 ...
DefineConstant[
  n = {8, Name "Parameters/elements per unit length"}
];

Point(1) = {0, 0, 0};
Point(2) = {1, 0, 0};
Point(3) = {1, 0.5, 0};
Point(4) = {0, 0.5, 0};
Point(5) = {1, 1, 0};
Point(6) = {0, 1, 0};

Line(1) = {1, 2};  // base
Line(2) = {2, 3};  // right side of lower
Line(3) = {3, 4};  // joint
Line(4) = {4, 1};  // left side of lower
Line(5) = {3, 5};  // right side of upper
Line(6) = {5, 6};  // top
Line(7) = {6, 4};  // left side of upper

Transfinite Curve{1, 3, 6} = Round(n) + 1;
Transfinite Curve{2, 4, 5, 7} = Round(n / 2) + 1;

Curve Loop(1) = {1, 2, 3, 4};
Curve Loop(2) = {-3, 5, 6, 7};
Plane Surface(1) = {1};
Plane Surface(2) = {2};

Physical Surface("lower") = {1};
Physical Surface("upper") = {2};
Physical Curve("base") = {1};
Physical Curve("lower_sides") = {2, 4};
Physical Curve("upper_sides") = {5, 7};
Physical Curve("top") = {6};
Physical Curve("joint") = {3};
