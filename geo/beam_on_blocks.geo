// The paper's example 1 (after Vodicka), half model: a beam 60 x 10 cm resting on two
// 10 x 10 cm blocks under its ends, outer block edges flush with the beam ends. Only the
// right half is drawn: the beam [0, 30] x [10, 20] (x = 0 is mid-span), the block
// [20, 30] x [0, 10] under its end. The beam's bottom over the block is the interface.
// Sizes are parameters (the paper: 2 cm on the outer curves, 0.1 cm on the interface):
//   gmsh -2 -setnumber h 1 -setnumber h_joint 0.05 ...
DefineConstant[
  h = {2, Name "Parameters/element size on the outer curves (cm)"},
  h_joint = {0.1, Name "Parameters/element size on the interface (cm)"}
];
L = 30; H = 10;      // half span, beam depth
xb = 20; B = 10;     // inner edge of the block, block size

Point(1) = {0, H, 0};          // beam, mid-span bottom
Point(2) = {xb, H, 0};         // inner corner: beam bottom meets the block
Point(3) = {L, H, 0};          // beam end, bottom (outer block corner)
Point(4) = {L, 2 * H, 0};
Point(5) = {0, 2 * H, 0};
Point(6) = {xb, H - B, 0};     // block base
Point(7) = {L, H - B, 0};

Line(1) = {1, 2};   // beam bottom, free
Line(2) = {2, 3};   // the interface
Line(3) = {3, 4};   // beam end, free
Line(4) = {4, 5};   // beam top, loaded
Line(5) = {5, 1};   // beam mid-span section: symmetry
Line(6) = {6, 7};   // block base, clamped
Line(7) = {7, 3};   // block outer side, free
Line(8) = {2, 6};   // block inner side, free

Transfinite Curve{1} = Round(xb / h) + 1;
Transfinite Curve{2} = Round((L - xb) / h_joint) + 1;
Transfinite Curve{3, 5} = Round(H / h) + 1;
Transfinite Curve{4} = Round(L / h) + 1;
Transfinite Curve{6} = Round((L - xb) / h) + 1;
Transfinite Curve{7, 8} = Round(B / h) + 1;

Curve Loop(1) = {1, 2, 3, 4, 5};      // beam, counter-clockwise
Curve Loop(2) = {6, 7, -2, 8};        // block, counter-clockwise
Plane Surface(1) = {1};
Plane Surface(2) = {2};

Physical Surface("beam") = {1};
Physical Surface("block") = {2};
Physical Curve("support") = {2};
Physical Curve("top") = {4};
Physical Curve("symmetry") = {5};
Physical Curve("clamp") = {6};
Physical Curve("free") = {1, 3, 7, 8};
