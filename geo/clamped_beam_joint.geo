// The paper's example 2: a beam 400 x 40 cm clamped at both ends, split at mid-span by a
// vertical joint shared by body A (left) and body B (right).
// Sizes are parameters:  gmsh -2 -setnumber h 2 -setnumber n_joint 208 ...
DefineConstant[
  h = {4, Name "Parameters/element size on the outer curves (cm)"},
  n_joint = {104, Name "Parameters/elements on the joint"}
];
L = 400; H = 40; xj = 200;

Point(1) = {0, 0, 0, h};
Point(2) = {xj, 0, 0, h};
Point(3) = {L, 0, 0, h};
Point(4) = {L, H, 0, h};
Point(5) = {xj, H, 0, h};
Point(6) = {0, H, 0, h};

Line(1) = {1, 2};  // bottom of A
Line(2) = {2, 3};  // bottom of B
Line(3) = {3, 4};  // clamped end of B
Line(4) = {4, 5};  // top of B
Line(5) = {5, 6};  // top of A
Line(6) = {6, 1};  // clamped end of A
Line(7) = {2, 5};  // the joint

Transfinite Curve{1, 2, 4, 5} = Round(xj / h) + 1;
Transfinite Curve{3, 6} = Round(H / h) + 1;
Transfinite Curve{7} = n_joint + 1;

Curve Loop(1) = {1, 7, 5, 6};
Curve Loop(2) = {2, 3, 4, -7};
Plane Surface(1) = {1};
Plane Surface(2) = {2};

Physical Surface("A") = {1};
Physical Surface("B") = {2};
Physical Curve("clamp") = {6, 3};
Physical Curve("top") = {5, 4};
Physical Curve("bottom") = {1, 2};
Physical Curve("joint") = {7};
