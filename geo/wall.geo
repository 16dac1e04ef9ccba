// A parametric masonry wall of `courses` courses of bricks on a clamped base: running bond
// (bond = 0.5: odd courses shifted by half a brick, with a part brick at each end) or stack
// bond (bond = 0), with an optional opening (a window: whole bricks left out).
//
// Every horizontal line between courses is cut at the head joints of the course below and
// of the course above, so each piece is shared by exactly one brick below and one above and
// gmsh meshes it once (the nodes of both sides match). Element size: brick_h / nj on every
// joint and face (Transfinite Curve), so joints hold nj elements across a brick height;
// inside each brick a structured grid of triangles (Transfinite Surface on its corners).
//
// Physical groups (few, for glob and default tables in the scene):
//   Surfaces  brick_1 .. brick_N, course by course from the base, left to right
//   Curves    joints (every head and bed joint: split per pair of bricks by sgbem),
//             base (under the first course), top, left, right (the wall's ends),
//             opening (the faces of the opening, when there is one)
//
// Points where three bricks meet (the T-junctions of a running bond, the crosses of a stack
// bond with two or more bricks per course) are junctions: sgbem keeps the joint rows there
// that are independent (README "Junctions"). A single column (bricks = 1, bond = 0) has none:
//   gmsh -2 -setnumber bricks 1 -setnumber bond 0 -setnumber courses 8 geo/wall.geo
// Units: any (the shipped scene uses m).
DefineConstant[
  courses = {6, Name "Parameters/courses (>= 1)"},
  bricks = {4, Name "Parameters/whole bricks per course (>= 1)"},
  brick_w = {0.4, Name "Parameters/brick width (with its share of the joints)"},
  brick_h = {0.2, Name "Parameters/brick height (course height)"},
  bond = {0.5, Name "Parameters/shift of odd courses in bricks: 0.5 running bond, 0 stack bond"},
  nj = {4, Name "Parameters/elements across a brick height (on head joints)"},
  open_from = {0, Name "Parameters/opening: first course left out (0: no opening)"},
  open_to = {0, Name "Parameters/opening: last course left out"},
  open_col = {0, Name "Parameters/opening: first brick left out in each of those courses (1-based)"},
  open_w = {0, Name "Parameters/opening: bricks left out per course"}
];

If (courses < 1 || bricks < 1 || brick_w <= 0 || brick_h <= 0 || bond < 0 || bond >= 1 || nj < 1)
  Error("wall.geo: need courses >= 1, bricks >= 1, sizes > 0, 0 <= bond < 1, nj >= 1");
  Abort;
EndIf

hs = brick_h / nj;                // element size
o = bond * brick_w;               // shift of odd courses
np = (o > 0) ? 2 * bricks + 1 : bricks + 1;   // points on each horizontal line

// x of point i on every horizontal line: the head joints of both courses it separates.
// Running bond: 0, o, w, w + o, 2w, ..., L; stack bond: 0, w, ..., L.
For j In {0:courses}
  For i In {0:np - 1}
    If (o > 0)
      x = (i % 2 == 0) ? (i / 2) * brick_w : ((i - 1) / 2) * brick_w + o;
    Else
      x = i * brick_w;
    EndIf
    Point(1 + j * np + i) = {x, j * brick_h, 0, hs};
  EndFor
EndFor

// Horizontal pieces: line hb + j * np + i from point i to i + 1 of line j.
hb = 1 + (courses + 1) * np;
For j In {0:courses}
  For i In {0:np - 2}
    Line(hb + j * np + i) = {1 + j * np + i, 1 + j * np + i + 1};
    x0 = (o > 0) ? ((i % 2 == 0) ? (i / 2) * brick_w : ((i - 1) / 2) * brick_w + o) : i * brick_w;
    x1 = (o > 0) ? ((i % 2 == 1) ? ((i + 1) / 2) * brick_w : (i / 2) * brick_w + o) : (i + 1) * brick_w;
    Transfinite Curve{hb + j * np + i} = Ceil((x1 - x0) / hs - 1e-9) + 1;
  EndFor
EndFor

// The brick edges of course j, as point indices on its lines: even courses (and every
// course of a stack bond) 0, 2, 4, ..., np - 1 (running) or 0, 1, ..., np - 1 (stack);
// odd courses of a running bond 0, 1, 3, ..., np - 2, np - 1.
// Vertical lines: vb + j * np + i from point i of line j up to point i of line j + 1.
vb = hb + (courses + 1) * np;
nbrick = 0;
// occ[(j + 1) * W + i + 1] = 1 where piece i of course j lies in a brick (0 in the opening,
// and in the padding rows j = -1, courses and columns i = -1, np - 1, so that no index is
// out of range: gmsh evaluates both branches of `?:`).
W = np + 1;
occ[] = {};
For k In {0:(courses + 2) * W - 1}
  occ[] += {0};
EndFor
For j In {0:courses - 1}
  edges[] = {};
  If (o > 0 && j % 2 == 1)
    edges[] = {0};
    For i In {1:np - 2:2}
      edges[] += {i};
    EndFor
    edges[] += {np - 1};
  ElseIf (o > 0)
    For i In {0:np - 1:2}
      edges[] += {i};
    EndFor
  Else
    For i In {0:np - 1}
      edges[] += {i};
    EndFor
  EndIf
  For e In {0:#edges[] - 1}
    Line(vb + j * np + edges[e]) = {1 + j * np + edges[e], 1 + (j + 1) * np + edges[e]};
    Transfinite Curve{vb + j * np + edges[e]} = nj + 1;
  EndFor
  // Bricks of course j: between consecutive edges; left out in the opening.
  For e In {0:#edges[] - 2}
    a = edges[e];
    b = edges[e + 1];
    out = (open_w > 0 && j + 1 >= open_from && j + 1 <= open_to && e + 1 >= open_col && e + 1 < open_col + open_w);
    If (!out)
      loop[] = {};
      For i In {a:b - 1}
        loop[] += {hb + j * np + i};
        occ[(j + 1) * W + i + 1] = 1;
      EndFor
      loop[] += {vb + j * np + b};
      For i In {b - 1:a:-1}
        loop[] += {-(hb + (j + 1) * np + i)};
      EndFor
      loop[] += {-(vb + j * np + a)};
      nbrick += 1;
      Curve Loop(nbrick) = loop[];
      Plane Surface(nbrick) = {nbrick};
      // A structured mesh inside (the grid of the interior fields): the boundary's nodes
      // are those of the curves either way, and gmsh's unstructured 2D mesher took 6 s of a
      // 45 x 45 wall's 6.5 s (this 0.06 s).
      Transfinite Surface{nbrick} = {1 + j * np + a, 1 + j * np + b, 1 + (j + 1) * np + b, 1 + (j + 1) * np + a};
      Physical Surface(Sprintf("brick_%g", nbrick)) = {nbrick};
    EndIf
  EndFor
EndFor

// Groups by the bricks on either side: bricks on both sides make a joint.
joints[] = {};
base[] = {};
top[] = {};
ends_l[] = {};
ends_r[] = {};
opening[] = {};
For j In {0:courses}
  For i In {0:np - 2}
    below = occ[j * W + i + 1];
    above = occ[(j + 1) * W + i + 1];
    c = hb + j * np + i;
    If (below && above)
      joints[] += {c};
    ElseIf (j == 0 && above)
      base[] += {c};
    ElseIf (j == courses && below)
      top[] += {c};
    ElseIf (below || above)
      opening[] += {c};
    EndIf
  EndFor
EndFor
For j In {0:courses - 1}
  For i In {0:np - 1}
    If (i == 0 || i == np - 1 || !(o > 0) || (j % 2 == 1 && i % 2 == 1) || (j % 2 == 0 && i % 2 == 0))
      l = occ[(j + 1) * W + i];
      r = occ[(j + 1) * W + i + 1];
      c = vb + j * np + i;
      If (l && r)
        joints[] += {c};
      ElseIf (i == 0 && r)
        ends_l[] += {c};
      ElseIf (i == np - 1 && l)
        ends_r[] += {c};
      ElseIf (l || r)
        opening[] += {c};
      EndIf
    EndIf
  EndFor
EndFor
Physical Curve("joints") = {joints[]};
Physical Curve("base") = {base[]};
Physical Curve("top") = {top[]};
Physical Curve("left") = {ends_l[]};
Physical Curve("right") = {ends_r[]};
If (#opening[] > 0)
  Physical Curve("opening") = {opening[]};
EndIf
