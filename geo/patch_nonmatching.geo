// Contact patch test with independent meshes (the set-up of Code_Aster's SSNP170): two
// blocks, "lower" [0,W] x [0,H] and "upper" [0,W] x [H,2H], each drawn with its own points
// and curves, so that gmsh meshes the two sides of the contact on their own: n_lower
// elements on the top of the lower block, n_upper on the bottom of the upper one. The
// Physical Curve "contact" holds both facing curves; sgbem pairs them from the geometry.
// Sizes are parameters:  gmsh -2 -setnumber n_lower 13 -setnumber n_upper 5 ...
Geometry.AutoCoherence = 0;   // keep the coincident points and curves of the two blocks apart
DefineConstant[
  n_lower = {10, Name "Parameters/elements under the interface"},
  n_upper = {7, Name "Parameters/elements above the interface"},
  n_side = {4, Name "Parameters/elements on each side and on the top and base"}
];
W = 2; H = 1;

Point(1) = {0, 0, 0};
Point(2) = {W, 0, 0};
Point(3) = {W, H, 0};
Point(4) = {0, H, 0};
Point(5) = {0, H, 0};        // the upper block's own corners on y = H
Point(6) = {W, H, 0};
Point(7) = {W, 2 * H, 0};
Point(8) = {0, 2 * H, 0};

Line(1) = {1, 2};  // base
Line(2) = {2, 3};  // right side of lower
Line(3) = {3, 4};  // top of lower: one side of the contact
Line(4) = {4, 1};  // left side of lower
Line(5) = {5, 6};  // bottom of upper: the other side of the contact
Line(6) = {6, 7};  // right side of upper
Line(7) = {7, 8};  // top (loaded)
Line(8) = {8, 5};  // left side of upper

Transfinite Curve{3} = Round(n_lower) + 1;
Transfinite Curve{5} = Round(n_upper) + 1;
Transfinite Curve{1, 2, 4, 6, 7, 8} = Round(n_side) + 1;

Curve Loop(1) = {1, 2, 3, 4};
Curve Loop(2) = {5, 6, 7, 8};
Plane Surface(1) = {1};
Plane Surface(2) = {2};

Physical Surface("upper") = {2};
Physical Surface("lower") = {1};
Physical Curve("contact") = {3, 5};
Physical Curve("lower_top") = {3};      // the two sides on their own, for `between`
Physical Curve("upper_bottom") = {5};
Physical Curve("top") = {7};
Physical Curve("base") = {1};
Physical Curve("left") = {4, 8};
Physical Curve("right") = {2, 6};
