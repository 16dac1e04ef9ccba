// Contact patch test: two blocks, "lower" [0,W] x [0,H] and "upper" [0,W] x [H,2H], touching
// along the shared curve y = H. Both blocks are meshed uniformly, the upper one with a
// different element count on its sides so that the two bodies' meshes differ.
// Sizes are parameters:  gmsh -2 -setnumber n 16 ...
DefineConstant[
  n = {8, Name "Parameters/elements along the contact"}
];
W = 2; H = 1;

Point(1) = {0, 0, 0};
Point(2) = {W, 0, 0};
Point(3) = {W, H, 0};
Point(4) = {0, H, 0};
Point(5) = {W, 2 * H, 0};
Point(6) = {0, 2 * H, 0};

Line(1) = {1, 2};  // base of lower
Line(2) = {2, 3};  // right side of lower
Line(3) = {4, 3};  // the contact, drawn left to right
Line(4) = {4, 1};  // left side of lower
Line(5) = {3, 5};  // right side of upper
Line(6) = {5, 6};  // top (loaded)
Line(7) = {6, 4};  // left side of upper

Transfinite Curve{1, 3} = Round(n) + 1;
Transfinite Curve{6} = Round(n / 2) + 1;
Transfinite Curve{2, 4} = Round(n / 2) + 1;
Transfinite Curve{5, 7} = Round(n / 4) + 2;

Curve Loop(1) = {1, 2, -3, 4};
Curve Loop(2) = {3, 5, 6, 7};
Plane Surface(1) = {1};
Plane Surface(2) = {2};

Physical Surface("upper") = {2};
Physical Surface("lower") = {1};
Physical Curve("contact") = {3};
Physical Curve("top") = {6};
Physical Curve("base") = {1};
Physical Curve("rollers") = {2, 4, 5, 7};
