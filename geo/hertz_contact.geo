// Hertz line contact, symmetric half model (x >= 0): two blocks W x H, "upper" on top of
// "lower", touching along the straight shared curve y = 0. The curvature is not drawn: the
// scene gives the initial gap x^2/(2R) of two cylinders of equivalent radius R.
// The contact curve is uniform (size h_fine) on [0, a_fine], where the contact zone lies,
// then graded geometrically up to h at x = W; the symmetry edges x = 0 are graded the same
// way from h_fine away from the contact point.
// Sizes are parameters:  gmsh -2 -setnumber h_fine 0.05 -setnumber a_fine 5 ...
DefineConstant[
  h_fine = {0.1, Name "Parameters/element size on the contact segment"},
  a_fine = {4.5, Name "Parameters/length of the uniform contact segment from the axis"},
  h = {5, Name "Parameters/element size on the outer curves"}
];
W = 50; H = 50;

Point(1) = {0, 0, 0};         // first contact point, on the axis
Point(2) = {a_fine, 0, 0};
Point(3) = {W, 0, 0};
Point(4) = {W, H, 0};
Point(5) = {0, H, 0};
Point(6) = {W, -H, 0};
Point(7) = {0, -H, 0};

Line(1) = {1, 2};   // contact, uniform
Line(2) = {2, 3};   // contact, graded
Line(3) = {3, 4};   // free side of upper
Line(4) = {4, 5};   // top (loaded)
Line(5) = {5, 1};   // symmetry edge of upper
Line(6) = {3, 6};   // free side of lower
Line(7) = {6, 7};   // base
Line(8) = {7, 1};   // symmetry edge of lower

Transfinite Curve{1} = Round(a_fine / h_fine) + 1;
// Geometric grading from h_fine to h over the length S: ratio r, n elements.
S = W - a_fine;
r = (S - h_fine) / (S - h);
Transfinite Curve{2} = Round(1 + Log(h / h_fine) / Log(r)) + 1 Using Progression r;
S = H;
r2 = (S - h_fine) / (S - h);
N2 = Round(1 + Log(h / h_fine) / Log(r2));
Transfinite Curve{5} = N2 + 1 Using Progression 1 / r2;
Transfinite Curve{8} = N2 + 1 Using Progression 1 / r2;
Transfinite Curve{3, 4, 6, 7} = Round(W / h) + 1;

Curve Loop(1) = {-2, -1, -5, -4, -3};   // upper, counter-clockwise
Curve Loop(2) = {1, 2, 6, 7, 8};        // lower, counter-clockwise
Plane Surface(1) = {1};
Plane Surface(2) = {2};

Physical Surface("upper") = {1};
Physical Surface("lower") = {2};
Physical Curve("contact") = {1, 2};
Physical Curve("top") = {4};
Physical Curve("base") = {7};
Physical Curve("symmetry") = {5, 8};
Physical Curve("sides") = {3, 6};
