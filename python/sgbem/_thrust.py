"""The thrust line of one archived state, computed from the archive as sgbem computes the
VTK block "thrust" (vtk/thrust_NNNN.vtu; docs/thrust.md): per joint (interface) the
resultant of its pairs' nodal forces (traction times tributary length) and its point of
application, a line through every body between its two loaded joints, and for a body with
more a hub on the line of action of the resultant of its bed joints.

The sums run pair by pair in sgbem's order, in Python floats, so that the points and values
are those of the VTK file bit for bit (numpy's sums add in another order)."""

import math

import numpy as np

from ._archive import _tributary

# Relative tolerance of `inside` and `in_closed_part` (a point at a joint's end is inside up
# to the rounding of the sums).
EDGE_TOLERANCE = 1e-9
# A joint is a bed joint below a body where the body's outward normal points down by more
# than this (cos 60 degrees), above where it points up by more.
BED = 0.5

VERTEX, LINE = 1, 3


def _sum(values):
    """A sum added from the first value on, starting from -0.0 as sgbem's sums do."""
    total = -0.0
    for v in values:
        total += v
    return total


class _Joint:
    """One joint's resultant in a state: normal (N, compression positive), tangential (T),
    force and moment (about the first pair, `about`) on the first body, the mean outward
    normal, and where it carries a normal force its point of application."""

    def __init__(self, x, s, w, normal, status, traction, thickness):
        tn, ts = traction[:, 1].tolist(), traction[:, 0].tolist()
        w, s = w.tolist(), s.tolist()
        x, normal = x.tolist(), normal.tolist()
        closed = (status == 1).tolist()
        self.forces = [a * b for a, b in zip(tn, w)]
        tangential = _sum(a * b for a, b in zip(ts, w))
        total = _sum(self.forces)
        magnitude = _sum(abs(p) for p in self.forces)

        def span(only_closed):
            lo, hi = math.inf, -math.inf
            for sj, wj, cj in zip(s, w, closed):
                if wj > 0.0 and (not only_closed or cj):
                    lo, hi = min(lo, sj), max(hi, sj)
            return lo, hi

        self.about = x[0] if x else [0.0, 0.0]
        ax, ay = self.about
        f, m, n = [0.0, 0.0], 0.0, [0.0, 0.0]
        for tnj, tsj, wj, xj, nj in zip(tn, ts, w, x, normal):
            fj = [(tnj * nj[0] - tsj * nj[1]) * wj, (tnj * nj[1] + tsj * nj[0]) * wj]
            f = [f[0] + fj[0], f[1] + fj[1]]
            arm = [xj[0] - ax, xj[1] - ay]
            m += arm[0] * fj[1] - arm[1] * fj[0]
            n = [n[0] + nj[0] * wj, n[1] + nj[1] * wj]
        length = float(np.hypot(n[0], n[1]))
        self.normal_mean = [n[0] / length, n[1] / length] if length > 0.0 else n
        lo, hi = span(False)
        length = hi - lo if hi >= lo else 0.0
        self.point = None
        if magnitude > 0.0 and total != 0.0 and length > 0.0:
            def mean(v):
                return _sum(a * p for a, p in zip(v, self.forces)) / total

            sc = mean(s)
            half = 0.5 * length
            e = sc - 0.5 * (lo + hi)
            slack = EDGE_TOLERANCE * length
            c_lo, c_hi = span(True)
            self.point = {
                "x": [ax + mean([xj[0] - ax for xj in x]), ay + mean([xj[1] - ay for xj in x])],
                "e": e, "e_over_half_length": e / half,
                "inside": abs(e) <= half + slack,
                "in_closed_part": c_lo - slack <= sc <= c_hi + slack,
            }
        self.normal = -total * thickness
        self.tangential = tangential * thickness
        self.force = [f[0] * thickness, f[1] * thickness]
        self.moment = m * thickness

    def at_point(self, v):
        """A per-pair vector weighted by the normal forces: its value at the point."""
        total = _sum(self.forces)
        acc = [0.0, 0.0]
        for p, vj in zip(self.forces, v.tolist()):
            acc = [acc[0] + p * vj[0], acc[1] + p * vj[1]]
        return [acc[0] / total, acc[1] / total]


def _down(body_forces):
    """Each body's "down": its body force's direction, -y without one (or a zero one)."""
    out = []
    for fx, fy in body_forces:
        length = float(np.hypot(fx, fy))
        ok = length > 0.0 and math.isfinite(length)
        out.append([fx / length, fy / length] if ok else [0.0, -1.0])
    return out


def _state_body_forces(run, f, st):
    """The bodies' body forces in the state (NaN: none): the state's own where the archive
    keeps them (they differ from the bodies': pseudo-time, collapse search), else the
    bodies' attributes."""
    if "body_force" in st:
        return np.asarray(st["body_force"], dtype=float).reshape(-1, 2).tolist()
    out = []
    for _, gname in run._bodies:
        bf = f["bodies"][gname].attrs.get("body_force")
        out.append([math.nan, math.nan] if bf is None else np.asarray(bf, float).tolist())
    return out


def _hub(group, joints, seen):
    """The point on the line of action of the resultant of joints `group` nearest to the
    centre of their normal forces, taken relative to the first joint's first pair, and that
    resultant (on the body, times the thickness); None where there is none."""
    o = joints[group[0]].about
    r, m0, n, c = [0.0, 0.0], 0.0, 0.0, [0.0, 0.0]
    for k in group:
        fk, mk, _ = seen(k)
        nk = joints[k].normal
        px, py = joints[k].point["x"]
        p = [px - o[0], py - o[1]]
        a = [joints[k].about[0] - o[0], joints[k].about[1] - o[1]]
        r = [r[0] + fk[0], r[1] + fk[1]]
        m0 += mk + a[0] * fk[1] - a[1] * fk[0]
        n += nk
        c = [c[0] + nk * p[0], c[1] + nk * p[1]]
    r2 = r[0] * r[0] + r[1] * r[1]
    if n <= 0.0 or r2 == 0.0:
        return None
    m = [c[0] / n, c[1] / n]
    mm = m0 - (m[0] * r[1] - m[1] * r[0])
    return [o[0] + m[0] + mm * r[1] / r2, o[1] + m[1] - mm * r[0] / r2], r


def _state_joints(run, f, st):
    """The joints (`_Joint`) of state `st` in run order, each with its (first, second)
    body's index, and the state's displacements."""
    thickness = float(f.attrs.get("thickness", 1.0))
    u = np.asarray(st["u"], dtype=float).reshape(-1, 2)
    status = np.asarray(st["status"])
    traction = np.asarray(st["traction"], dtype=float).reshape(-1, 2)
    joints, bodies = [], []
    for i, (_, gname) in enumerate(run._interfaces):
        it = f["interfaces"][gname]
        lo, hi = run._pair_offset[i], run._pair_offset[i + 1]
        x = np.asarray(it["x"], dtype=float).reshape(-1, 2)
        a, b = int(it.attrs["body_a_index"]), int(it.attrs["body_b_index"])
        th = _Joint(x, np.asarray(it["s"], dtype=float), _tributary(it, x),
                    np.asarray(it["normal"], dtype=float).reshape(-1, 2), status[lo:hi],
                    traction[lo:hi], thickness)
        th.first_nodes = np.asarray(it["node_a"], dtype=np.int64)
        joints.append(th)
        bodies.append((a, b))
    return joints, bodies, u


def _loaded(run, joints, bodies):
    """Each body's loaded joints (those with a point of application), in run order."""
    loaded = [[] for _ in run._bodies]
    for j, (a, b) in enumerate(bodies):
        if joints[j].point is not None:
            for body in (a, b):
                if 0 <= body < len(loaded):
                    loaded[body].append(j)
    return loaded


def _hubs(run, f, st, joints, bodies, loaded):
    """The hubs of the bodies with more than two loaded joints (docs/thrust.md, "Bodies with
    more joints"), in body order, as sgbem's post/thrust.rs `hubs` finds them: per hub the
    body's index, the hub, the resultant of its group of joints on the body, whether that
    group lies below (along the body's "down") and the body's loaded joints."""
    down = _down(_state_body_forces(run, f, st))
    out = []
    for body, js in enumerate(loaded):
        if len(js) <= 2:
            continue
        d = down[body]

        def seen(j, body=body, d=d):
            t = joints[j]
            sign = 1.0 if bodies[j][0] == body else -1.0
            n = t.normal_mean
            return ([sign * t.force[0], sign * t.force[1]], sign * t.moment,
                    sign * (n[0] * d[0] + n[1] * d[1]))

        below = [j for j in js if seen(j)[2] > BED]
        group = below or [j for j in js if -seen(j)[2] > BED]
        found = _hub(group, joints, seen) if group else None
        if found is not None:
            out.append((body, found[0], found[1], bool(below), js))
    return out


def hub_rows(run, f, k):
    """The hubs of state `k` as thrust_hubs.csv lists them for the final state: per hub a
    dict of body (its index), x, y, R_x, R_y (the resultant on the body of its group of
    joints, times the thickness), group ("below" or "above") and joints (how many loaded
    joints it joins)."""
    st = f["states"][f"{k:04}"]
    joints, bodies, _ = _state_joints(run, f, st)
    rows = []
    for body, x, r, below, js in _hubs(run, f, st, joints, bodies,
                                       _loaded(run, joints, bodies)):
        rows.append({"body": body, "x": x[0] + 0.0, "y": x[1] + 0.0, "R_x": r[0] + 0.0,
                     "R_y": r[1] + 0.0, "group": "below" if below else "above",
                     "joints": len(js)})
    return rows


def thrust_line(run, f, k):
    """The thrust block of state `k` as plain arrays: `points` (n x 2), `cells` (a list of
    point-index tuples), `cell_types` (VTK codes: 1 vertex, 3 line) and the point data
    N, T, e, e_over_half_length (float, NaN at a hub), inside, in_closed_part (1 yes, 0 no,
    -1 at a hub), joint (the interface's index in the run, -1 at a hub) and displacement
    (n x 2: the first body's, weighted as the point is; at a hub the mean of its joints')."""
    st = f["states"][f"{k:04}"]
    cols = {c: [] for c in ("points", "displacement", "N", "T", "e", "e_over_half_length",
                            "inside", "in_closed_part", "joint")}

    def push(x, disp, joint, values, flags):
        cols["points"].append(x)
        cols["displacement"].append(disp)
        cols["joint"].append(joint)
        for c, v in zip(("N", "T", "e", "e_over_half_length"), values):
            cols[c].append(v)
        cols["inside"].append(flags[0])
        cols["in_closed_part"].append(flags[1])

    joints, bodies, u = _state_joints(run, f, st)
    point_of = []
    for i, th in enumerate(joints):
        point_of.append(None)
        if th.point is not None:
            a = bodies[i][0]
            ua = u[run._node_offset[a] + th.first_nodes]
            point_of[i] = len(cols["joint"])
            p = th.point
            push(p["x"], th.at_point(ua), i, (th.normal, th.tangential, p["e"],
                                              p["e_over_half_length"]),
                 (int(p["inside"]), int(p["in_closed_part"])))
    cells = [(j,) for j in range(len(cols["joint"]))]
    types = [VERTEX] * len(cells)
    loaded = _loaded(run, joints, bodies)
    for js in loaded:
        if len(js) == 2:
            cells.append((point_of[js[0]], point_of[js[1]]))
            types.append(LINE)
    for _, hub, _, _, js in _hubs(run, f, st, joints, bodies, loaded):
        ends = [point_of[j] for j in js]
        ux, uy = 0.0, 0.0
        for e in ends:
            ux, uy = ux + cols["displacement"][e][0], uy + cols["displacement"][e][1]
        m = float(max(len(ends), 1))
        at = len(cols["joint"])
        push(hub, [ux / m, uy / m], -1, (math.nan,) * 4, (-1, -1))
        cells.append((at,))
        types.append(VERTEX)
        for e in ends:
            cells.append((e, at))
            types.append(LINE)
    out = {"cells": cells, "cell_types": types}
    for c, v in cols.items():
        if c in ("inside", "in_closed_part", "joint"):
            out[c] = np.asarray(v, dtype=np.int32)
        elif c in ("points", "displacement"):
            out[c] = np.asarray(v, dtype=float).reshape(len(v), 2) + 0.0
        else:
            out[c] = np.asarray(v, dtype=float) + 0.0
    return out
