// Shrink fit: a hollow shaft (radii a < b) pressed into a hub (radii b < c); the shaft and
// the hub share the circle r = b ("fit"), where the scene gives the interference as a
// negative gap. The hole r = a carries the torque, the hub's outer circle r = c is held
// tangentially (rigid modes), free radially.
// Elements per quarter circle:  gmsh -2 -setnumber n 32 ...
DefineConstant[
  n = {32, Name "Parameters/elements per quarter circle"},
  a = {0.25, Name "Parameters/radius of the shaft's hole"},
  b = {0.5, Name "Parameters/radius of the fit"},
  c = {1.0, Name "Parameters/outer radius of the hub"}
];
Point(1) = {0, 0, 0};
For k In {0:3}
  Point(10 + k) = {a * Cos(k * Pi / 2), a * Sin(k * Pi / 2), 0};
  Point(20 + k) = {b * Cos(k * Pi / 2), b * Sin(k * Pi / 2), 0};
  Point(30 + k) = {c * Cos(k * Pi / 2), c * Sin(k * Pi / 2), 0};
EndFor
For k In {0:3}
  Circle(10 + k) = {10 + k, 1, 10 + (k + 1) % 4};
  Circle(20 + k) = {20 + k, 1, 20 + (k + 1) % 4};
  Circle(30 + k) = {30 + k, 1, 30 + (k + 1) % 4};
EndFor
Transfinite Curve{10:13} = Round(n / 2) + 1;
Transfinite Curve{20:23} = n + 1;
Transfinite Curve{30:33} = n + 1;

Curve Loop(1) = {20, 21, 22, 23};   // fit, counter-clockwise
Curve Loop(2) = {10, 11, 12, 13};   // hole
Curve Loop(3) = {30, 31, 32, 33};   // outer
Plane Surface(1) = {1, 2};          // shaft
Plane Surface(2) = {3, 1};          // hub

Physical Surface("shaft") = {1};
Physical Surface("hub") = {2};
Physical Curve("fit") = {20:23};
Physical Curve("hole") = {10:13};
Physical Curve("outer") = {30:33};
