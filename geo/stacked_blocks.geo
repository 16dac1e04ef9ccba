// A stack of nb blocks w x hb, each drawn on its own (its own points and curves) and meshed
// on its own: block i has 4 + 3i elements on its bottom and 5 + 2i on its top, so no joint
// has matching nodes; every other block is shifted right by `shift`. Nothing in the drawing
// says which faces touch: a scene with [contact] finds the joints.
// Parameters:  gmsh -2 -setnumber nb 5 -setnumber shift 0.1 ...
// (`sink` > 0 draws each block that far into the one below: an overlap, for the tests.)
Geometry.AutoCoherence = 0;   // keep the coincident corners of neighbouring blocks apart
DefineConstant[
  nb = {3, Name "Parameters/blocks"},
  w = {1, Name "Parameters/block width"},
  hb = {0.5, Name "Parameters/block height"},
  shift = {0.25, Name "Parameters/shift of every other block"},
  sink = {0, Name "Parameters/overlap of each block into the one below (a drawing error)"}
];
faces[] = {};
For i In {0 : nb - 1}
  x0 = (i % 2) * shift;
  y0 = i * (hb - sink);
  p = newp;
  Point(p) = {x0, y0, 0};
  Point(p + 1) = {x0 + w, y0, 0};
  Point(p + 2) = {x0 + w, y0 + hb, 0};
  Point(p + 3) = {x0, y0 + hb, 0};
  l = newl;
  Line(l) = {p, p + 1};           // bottom
  Line(l + 1) = {p + 1, p + 2};   // right side
  Line(l + 2) = {p + 2, p + 3};   // top
  Line(l + 3) = {p + 3, p};       // left side
  Transfinite Curve{l} = 4 + 3 * i + 1;
  Transfinite Curve{l + 2} = 5 + 2 * i + 1;
  Transfinite Curve{l + 1, l + 3} = 3;
  c = newll;
  Curve Loop(c) = {l, l + 1, l + 2, l + 3};
  s = news;
  Plane Surface(s) = {c};
  Physical Surface(Sprintf("block_%g", i)) = {s};
  If (i == 0)
    Physical Curve("base") = {l};
  Else
    faces[] += {l};
  EndIf
  faces[] += {l + 1, l + 2, l + 3};
EndFor
Physical Curve("faces") = faces[];
