// Frictional line contact (Cattaneo-Mindlin), full model: two blocks 2W x H of the same
// material, "upper" on top of "lower", touching along the straight shared curve y = 0; the
// curvature enters as the initial gap x^2/(2R) given by the scene. The contact curve is
// uniform (size h_fine) on [-a_fine, a_fine], where the contact zone lies, and graded
// geometrically up to h at x = +-W.
// Sizes are parameters:  gmsh -2 -setnumber h_fine 0.1 ...
DefineConstant[
  h_fine = {0.1, Name "Parameters/element size on the contact segment"},
  a_fine = {4, Name "Parameters/half-length of the uniform contact segment"},
  h = {5, Name "Parameters/element size on the outer curves"}
];
W = 50; H = 50;

Point(1) = {-W, 0, 0};
Point(2) = {-a_fine, 0, 0};
Point(3) = {a_fine, 0, 0};
Point(4) = {W, 0, 0};
Point(5) = {W, H, 0};
Point(6) = {-W, H, 0};
Point(7) = {W, -H, 0};
Point(8) = {-W, -H, 0};

Line(1) = {1, 2};   // contact, graded towards the middle
Line(2) = {2, 3};   // contact, uniform
Line(3) = {3, 4};   // contact, graded outwards
Line(4) = {4, 5};   // right side of upper
Line(5) = {5, 6};   // top (loaded)
Line(6) = {6, 1};   // left side of upper
Line(7) = {4, 7};   // right side of lower
Line(8) = {7, 8};   // base
Line(9) = {8, 1};   // left side of lower

Transfinite Curve{2} = Round(2 * a_fine / h_fine) + 1;
// Geometric grading from h_fine to h over the length S: ratio r, n elements.
S = W - a_fine;
r = (S - h_fine) / (S - h);
N = Round(1 + Log(h / h_fine) / Log(r));
Transfinite Curve{3} = N + 1 Using Progression r;
Transfinite Curve{1} = N + 1 Using Progression 1 / r;
Transfinite Curve{4, 6, 7, 9} = Round(H / h) + 1;
Transfinite Curve{5, 8} = Round(2 * W / h) + 1;

Curve Loop(1) = {1, 2, 3, 4, 5, 6};      // upper, traversed with the body on the left
Curve Loop(2) = {-3, -2, -1, -9, -8, -7}; // lower
Plane Surface(1) = {1};
Plane Surface(2) = {2};

Physical Surface("upper") = {1};
Physical Surface("lower") = {2};
Physical Curve("contact") = {1, 2, 3};
Physical Curve("top") = {5};
Physical Curve("base") = {8};
Physical Curve("sides") = {4, 6, 7, 9};
