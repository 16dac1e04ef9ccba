// Kirsch plate, quarter model: the square [0, 1] x [0, 1] minus the hole r < 0.2 around the
// origin (plane strain). The outer edges x = 1 and y = 1 carry the exact Kirsch
// displacements, the axes are symmetry lines, the hole is traction-free.
// `n` elements per unit length on the outer edges; the hole is `q` times finer and the
// symmetry edges are graded geometrically between the two:  gmsh -2 -setnumber n 24 ...
DefineConstant[
  n = {12, Name "Parameters/elements per unit length on the outer edges"},
  q = {4, Name "Parameters/refinement factor at the hole"}
];
a = 0.2; W = 1;

Point(1) = {0, 0, 0};  // centre of the hole
Point(2) = {a, 0, 0};
Point(3) = {W, 0, 0};
Point(4) = {W, W, 0};
Point(5) = {0, W, 0};
Point(6) = {0, a, 0};

Line(1) = {2, 3};        // symmetry y = 0
Line(2) = {3, 4};        // outer edge x = W
Line(3) = {4, 5};        // outer edge y = W
Line(4) = {5, 6};        // symmetry x = 0
Circle(5) = {6, 1, 2};   // the hole r = a

// Geometric grading on the symmetry edges from h/q at the hole to h at the outer edge.
h = 1 / n; hh = h / q;
r = (W - a - hh) / (W - a - h);
Na = Round(1 + Log(q) / Log(r));
Transfinite Curve{1} = Na + 1 Using Progression r;
Transfinite Curve{4} = Na + 1 Using Progression 1 / r;
Transfinite Curve{2, 3} = Round(n * W) + 1;
Transfinite Curve{5} = Round(Pi * a / 2 / hh) + 1;

Curve Loop(1) = {1, 2, 3, 4, 5};
Plane Surface(1) = {1};

Physical Surface("plate") = {1};
Physical Curve("hole") = {5};
Physical Curve("outer") = {2, 3};
Physical Curve("symmetry") = {1, 4};
