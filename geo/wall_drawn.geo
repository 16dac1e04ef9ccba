// A parametric masonry wall drawn brick by brick, as a user who draws each brick as its own
// rectangle would: `courses` courses of bricks, running bond (bond = 0.5: odd courses
// shifted by half a brick, with a part brick at each end) or stack bond (bond = 0), on a
// foundation block drawn on its own. Nothing in the drawing says which faces touch: a scene
// with [contact] finds the joints (pipelines/wall_drawn.toml); geo/wall.geo draws the same
// wall conforming (shared joint lines, matching nodes).
//
// Every brick has its own points and curves and is meshed on its own, so that no joint has
// matching nodes: with hs = brick_h / nj, a brick of width w has ceil(w / hs) elements on its
// bottom and one more on its top, nj on its left side and nj + 1 on its right side; the
// foundation's top has one element more than ceil(L / hs) (L the wall's length). A brick's
// top element under a head joint of the course above faces two bricks: [contact] cuts it
// (unless the joint meets it within 5 % of a node); with a bond other than 0.5 so is a
// brick's bottom element over a head joint of the course below.
//
// Physical groups (few, for glob and default tables in the scene):
//   Surfaces  brick_1 .. brick_N, course by course from the base, left to right;
//             foundation (under the first course, as long as the wall, found_h high)
//   Curves    base (under the foundation), top (the last course's tops), left, right (the
//             wall's ends, courses only), faces (every other curve: the joints' candidates
//             and the foundation's sides). Every curve is in a group: gmsh 4.8 drops the
//             curves of no group once a Physical group exists.
//
// Joints drawn (running bond, bricks = b whole bricks per course, courses = c):
//   b on the foundation, 2b per bed between courses (c - 1 beds), b - 1 head joints in an
//   even course and b in an odd one (tests/geometry_contact.rs counts them).
// Units: any (the shipped scene uses m).
Geometry.AutoCoherence = 0;   // keep the coincident corners of neighbouring bricks apart
DefineConstant[
  courses = {6, Name "Parameters/courses (>= 1)"},
  bricks = {4, Name "Parameters/whole bricks per course (>= 1)"},
  brick_w = {0.4, Name "Parameters/brick width (with its share of the joints)"},
  brick_h = {0.2, Name "Parameters/brick height (course height)"},
  bond = {0.5, Name "Parameters/shift of odd courses in bricks: 0.5 running bond, 0 stack bond"},
  nj = {4, Name "Parameters/elements on a brick's left side (nj + 1 on its right side)"},
  found_h = {0.2, Name "Parameters/foundation height"}
];

If (courses < 1 || bricks < 1 || brick_w <= 0 || brick_h <= 0 || bond < 0 || bond >= 1 || nj < 1 || found_h <= 0)
  Error("wall_drawn.geo: need courses >= 1, bricks >= 1, sizes > 0, 0 <= bond < 1, nj >= 1");
  Abort;
EndIf

hs = brick_h / nj;                // element size
o = bond * brick_w;               // shift of odd courses
L = bricks * brick_w;             // the wall's length
g_top[] = {};
g_left[] = {};
g_right[] = {};
g_faces[] = {};

// One brick: corner (bx, by), width bw; first (last) in its course when is_first (is_last),
// in the last course when is_top. Appends its curves to the groups.
Macro Brick
  p = newp;
  Point(p) = {bx, by, 0, hs};
  Point(p + 1) = {bx + bw, by, 0, hs};
  Point(p + 2) = {bx + bw, by + brick_h, 0, hs};
  Point(p + 3) = {bx, by + brick_h, 0, hs};
  l = newl;
  Line(l) = {p, p + 1};           // bottom
  Line(l + 1) = {p + 1, p + 2};   // right side
  Line(l + 2) = {p + 2, p + 3};   // top
  Line(l + 3) = {p + 3, p};       // left side
  nb = Ceil(bw / hs - 1e-9);
  Transfinite Curve{l} = nb + 1;
  Transfinite Curve{l + 2} = nb + 2;
  Transfinite Curve{l + 1} = nj + 2;
  Transfinite Curve{l + 3} = nj + 1;
  c = newll;
  Curve Loop(c) = {l, l + 1, l + 2, l + 3};
  s = news;
  Plane Surface(s) = {c};
  nbrick += 1;
  Physical Surface(Sprintf("brick_%g", nbrick)) = {s};
  g_faces[] += {l};
  If (is_last)
    g_right[] += {l + 1};
  Else
    g_faces[] += {l + 1};
  EndIf
  If (is_top)
    g_top[] += {l + 2};
  Else
    g_faces[] += {l + 2};
  EndIf
  If (is_first)
    g_left[] += {l + 3};
  Else
    g_faces[] += {l + 3};
  EndIf
Return

// The foundation: [0, L] x [-found_h, 0].
pf = newp;
Point(pf) = {0, -found_h, 0, hs};
Point(pf + 1) = {L, -found_h, 0, hs};
Point(pf + 2) = {L, 0, 0, hs};
Point(pf + 3) = {0, 0, 0, hs};
lf = newl;
Line(lf) = {pf, pf + 1};
Line(lf + 1) = {pf + 1, pf + 2};
Line(lf + 2) = {pf + 2, pf + 3};
Line(lf + 3) = {pf + 3, pf};
Transfinite Curve{lf} = Ceil(L / hs - 1e-9) + 1;
Transfinite Curve{lf + 2} = Ceil(L / hs - 1e-9) + 2;
Transfinite Curve{lf + 1, lf + 3} = Ceil(found_h / hs - 1e-9) + 1;
cf = newll;
Curve Loop(cf) = {lf, lf + 1, lf + 2, lf + 3};
sf = news;
Plane Surface(sf) = {cf};
g_faces[] += {lf + 1, lf + 2, lf + 3};

// The courses: even ones (and every course of a stack bond) of whole bricks from x = 0; odd
// ones of a running bond a part brick o wide, bricks - 1 whole ones, a part brick w - o wide.
nbrick = 0;
For j In {0:courses - 1}
  by = j * brick_h;
  is_top = (j == courses - 1);
  If (o > 0 && j % 2 == 1)
    n = bricks + 1;
  Else
    n = bricks;
  EndIf
  For i In {0:n - 1}
    If (o > 0 && j % 2 == 1)
      bx = (i == 0) ? 0 : o + (i - 1) * brick_w;
      bw = (i == 0) ? o : ((i == n - 1) ? brick_w - o : brick_w);
    Else
      bx = i * brick_w;
      bw = brick_w;
    EndIf
    is_first = (i == 0);
    is_last = (i == n - 1);
    Call Brick;
  EndFor
EndFor

Physical Surface("foundation") = {sf};
Physical Curve("base") = {lf};
Physical Curve("top") = {g_top[]};
Physical Curve("left") = {g_left[]};
Physical Curve("right") = {g_right[]};
Physical Curve("faces") = {g_faces[]};
