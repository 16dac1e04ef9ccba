"""Irregular stone masonry for gmsh: a wall of n stones, each drawn on its own.

The stones are the cells of a Voronoi tessellation of the wall's rectangle (W x H) around
n random sites, relaxed by Lloyd's iterations so that the stones come out roundish and of
similar size, and clipped to the rectangle; vertices closer than `merge` times the mean
stone size are merged (no sliver edges). The wall stands on a foundation block wider than
it. Every stone and the foundation are drawn with their own points and curves
(Geometry.AutoCoherence = 0): nothing in the drawing says which faces touch; a scene with
`[contact]` finds the joints (pipelines/stone_wall.toml).

Physical groups: Surfaces stone_1 .. stone_n (left to right, bottom up by their centres)
and foundation; Curves faces (every stone face and the foundation's top), base (under the
foundation), foundation_sides. Element size h on every curve (a parameter of the .geo:
gmsh -setnumber h 0.05 ...).

Usage: stones.py [--stones 220] [--width 6] [--height 3] [--seed 7] [--lloyd 4]
                 [--merge 0.08] [--out geo/stone_wall.geo]
Standard library only; the same arguments give the same file.
"""
import argparse
import math
import random


def clip(poly, a, b, c):
    """The part of polygon `poly` where a*x + b*y <= c (Sutherland-Hodgman, one edge)."""
    out = []
    n = len(poly)
    for i in range(n):
        p, q = poly[i], poly[(i + 1) % n]
        fp = a * p[0] + b * p[1] - c
        fq = a * q[0] + b * q[1] - c
        if fp <= 0:
            out.append(p)
        if (fp < 0 < fq) or (fq < 0 < fp):
            t = fp / (fp - fq)
            out.append((p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])))
    return out


def voronoi(sites, width, height):
    """The Voronoi cell of every site within the rectangle [0, width] x [0, height]."""
    box = [(0.0, 0.0), (width, 0.0), (width, height), (0.0, height)]
    cells = []
    for i, (xi, yi) in enumerate(sites):
        poly = box
        # Nearer sites first: the cell shrinks fast and most far sites clip nothing.
        order = sorted(range(len(sites)), key=lambda j: (sites[j][0] - xi) ** 2 + (sites[j][1] - yi) ** 2)
        for j in order:
            if j == i:
                continue
            xj, yj = sites[j]
            d2 = (xj - xi) ** 2 + (yj - yi) ** 2
            # No point of the cell is farther from site i than its farthest vertex: a site
            # more than twice that away cannot clip it.
            r2 = max((x - xi) ** 2 + (y - yi) ** 2 for x, y in poly)
            if d2 > 4.0 * r2:
                break
            # Points nearer to i than to j: 2 (xj - xi) x + 2 (yj - yi) y <= |j|^2 - |i|^2.
            poly = clip(poly, 2 * (xj - xi), 2 * (yj - yi), xj * xj + yj * yj - xi * xi - yi * yi)
        cells.append(poly)
    return cells


def centroid(poly):
    a = cx = cy = 0.0
    n = len(poly)
    for i in range(n):
        (x0, y0), (x1, y1) = poly[i], poly[(i + 1) % n]
        w = x0 * y1 - x1 * y0
        a += w
        cx += (x0 + x1) * w
        cy += (y0 + y1) * w
    return (cx / (3 * a), cy / (3 * a)), 0.5 * a


def merge_vertices(cells, tol, width, height):
    """Merges the vertices of all cells closer than tol into one point (union-find over a
    grid), so that neighbouring stones keep identical shared faces; drops repeated
    vertices and cells left with fewer than three."""
    pts = []
    index = {}
    for poly in cells:
        for p in poly:
            key = (round(p[0], 12), round(p[1], 12))
            if key not in index:
                index[key] = len(pts)
                pts.append(p)
    parent = list(range(len(pts)))

    def find(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    grid = {}
    cell = tol if tol > 0 else 1.0  # tol = 0: nothing merges, any grid will do
    for i, (x, y) in enumerate(pts):
        grid.setdefault((int(x // cell), int(y // cell)), []).append(i)
    for (gx, gy), members in grid.items():
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                for j in grid.get((gx + dx, gy + dy), []):
                    for i in members:
                        if i < j and math.dist(pts[i], pts[j]) < tol:
                            parent[find(i)] = find(j)
    # A merged point is the mean of its members, kept on the rectangle's edges where one of
    # them lies there.
    groups = {}
    for i in range(len(pts)):
        groups.setdefault(find(i), []).append(i)
    rep = {}
    for root, members in groups.items():
        x = sum(pts[i][0] for i in members) / len(members)
        y = sum(pts[i][1] for i in members) / len(members)
        for i in members:
            px, py = pts[i]
            if abs(px) < 1e-12 or abs(px - width) < 1e-12:
                x = px
            if abs(py) < 1e-12 or abs(py - height) < 1e-12:
                y = py
        rep[root] = (x, y)
    out = []
    for poly in cells:
        q = []
        for p in poly:
            r = rep[find(index[(round(p[0], 12), round(p[1], 12))])]
            if not q or q[-1] != r:
                q.append(r)
        while len(q) > 1 and q[0] == q[-1]:
            q.pop()
        if len(q) >= 3:
            out.append(q)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--stones", type=int, default=220)
    ap.add_argument("--width", type=float, default=6.0)
    ap.add_argument("--height", type=float, default=3.0)
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--lloyd", type=int, default=4)
    ap.add_argument("--merge", type=float, default=0.08)
    ap.add_argument("--out", default="geo/stone_wall.geo")
    a = ap.parse_args()
    if a.stones < 1:
        ap.error(f"--stones {a.stones}: give 1 or more")
    if not (a.width > 0 and a.height > 0 and math.isfinite(a.width * a.height)):
        ap.error(f"--width {a.width} --height {a.height}: give positive finite sizes")
    if a.lloyd < 0:
        ap.error(f"--lloyd {a.lloyd}: give 0 (plain Voronoi cells) or more")
    if not (0 <= a.merge < 1):
        ap.error(f"--merge {a.merge}: give a fraction of the stone size in [0, 1) (0: no merging)")
    rng = random.Random(a.seed)
    w, h = a.width, a.height
    sites = [(rng.uniform(0, w), rng.uniform(0, h)) for _ in range(a.stones)]
    for _ in range(a.lloyd):
        sites = [centroid(c)[0] for c in voronoi(sites, w, h)]
    cells = voronoi(sites, w, h)
    size = math.sqrt(w * h / a.stones)
    cells = merge_vertices(cells, a.merge * size, w, h)
    # Counter-clockwise, ordered bottom up then left to right by their centres.
    cells = [c if centroid(c)[1] > 0 else c[::-1] for c in cells]
    cells.sort(key=lambda c: (round(centroid(c)[0][1] / (0.5 * size)), centroid(c)[0][0]))

    # The joints: pairs of stones that share a face, and stones on the foundation.
    edges = {}
    for k, poly in enumerate(cells):
        for i in range(len(poly)):
            e = (poly[i], poly[(i + 1) % len(poly)])
            edges.setdefault(frozenset(e), set()).add(k)
    shared = {tuple(sorted(ks)) for ks in edges.values() if len(ks) == 2}
    on_base = {k for k, poly in enumerate(cells) for i in range(len(poly))
               if poly[i][1] == 0.0 and poly[(i + 1) % len(poly)][1] == 0.0}
    joints = len(shared) + len(on_base)

    lines = [
        f"// Irregular stone masonry: {len(cells)} stones (Voronoi cells of {a.stones} random",
        f"// sites, seed {a.seed}, {a.lloyd} Lloyd iterations, vertices merged within",
        f"// {a.merge} x the stone size) in a wall {w} x {h} on a foundation block; every stone",
        "// drawn on its own. Written by pipelines/stones.py "
        f"--stones {a.stones} --width {w} --height {h} --seed {a.seed} --lloyd {a.lloyd} "
        f"--merge {a.merge}: edit that, not this file.",
        f"// Joints: {joints} ({len(shared)} pairs of stones sharing a face, {len(on_base)} stones "
        "on the foundation).",
        "Geometry.AutoCoherence = 0;   // keep the stones' coincident points and curves apart",
        'DefineConstant[ h = {%g, Name "Parameters/element size"} ];' % (size / 4),
        "faces[] = {};",
    ]
    pt = ln = 0
    for k, poly in enumerate(cells, start=1):
        first = pt + 1
        for x, y in poly:
            pt += 1
            lines.append(f"Point({pt}) = {{{x!r}, {y!r}, 0, h}};")
        ids = []
        for i in range(len(poly)):
            ln += 1
            a_, b_ = first + i, first + (i + 1) % len(poly)
            lines.append(f"Line({ln}) = {{{a_}, {b_}}};")
            ids.append(ln)
        lines.append(f"Curve Loop({k}) = {{{', '.join(map(str, ids))}}};")
        lines.append(f"Plane Surface({k}) = {{{k}}};")
        lines.append(f'Physical Surface("stone_{k}") = {{{k}}};')
        lines.append(f"faces[] += {{{', '.join(map(str, ids))}}};")
    # The foundation: [-m, w + m] x [-hf, 0].
    m, hf = 0.1 * w, 0.2 * h
    n = len(cells) + 1
    corners = [(-m, -hf), (w + m, -hf), (w + m, 0.0), (-m, 0.0)]
    first = pt + 1
    for x, y in corners:
        pt += 1
        lines.append(f"Point({pt}) = {{{x!r}, {y!r}, 0, h}};")
    ids = []
    for i in range(4):
        ln += 1
        lines.append(f"Line({ln}) = {{{first + i}, {first + (i + 1) % 4}}};")
        ids.append(ln)
    lines += [
        f"Curve Loop({n}) = {{{', '.join(map(str, ids))}}};",
        f"Plane Surface({n}) = {{{n}}};",
        f'Physical Surface("foundation") = {{{n}}};',
        f"faces[] += {{{ids[2]}}};",
        'Physical Curve("faces") = faces[];',
        f'Physical Curve("base") = {{{ids[0]}}};',
        f'Physical Curve("foundation_sides") = {{{ids[1]}, {ids[3]}}};',
    ]
    with open(a.out, "w") as f:
        f.write("\n".join(lines) + "\n")
    print(f"{a.out}: {len(cells)} stones, {joints} joints, {pt} points, {ln} curves")


if __name__ == "__main__":
    main()
