#!/usr/bin/env python3
"""make accuracy: what accuracy costs in time.

For each closed-form benchmark (Lamé, compound cylinder, Kirsch, Timoshenko cantilever,
self-weight column) and for the paper's examples 1 (stick and slide) and 2, mesh the scene's
geo at several refinement levels, run `sgbem run` with each quadrature preset (fast,
standard, accurate) and record

  * benchmarks: the error against the exact field at the section points, as
    tests/convergence.rs measures it: max |u_h - u| / max |u| and
    max_c |sigma_h,c - sigma_c| / max_c |sigma_c| (maxima over every section point; the same
    over the points at least `interior` from every curve in the *_interior columns);
  * examples: the detached length (summary.json interfaces.<name>.detached_length, LCP),
    its relative change against the finest level run with `accurate`, and against the
    paper's value; also a sub-element estimate of the detachment front (the opening near a
    smooth contact edge grows as d^(3/2): opening^(2/3) of the last two open pairs is
    extrapolated linearly to zero);
  * the run time: timings.json stages.total, the minimum over repeats for short runs.

Each run uses a copy of the pipeline's scene (written under out/accuracy/runs/) with only the
outputs the study reads: no interior field, no VTK, no archived operators, final history
only (as tests/convergence.rs does), and `[solve] quadrature` set. The mesh and the output
folder are passed on the command line. The contact solver is the scene's (`both`: LCP and
QP) so that an example's time is that of the run a user makes.

Outputs in out/accuracy/: accuracy.csv, accuracy.md, accuracy_benchmarks.png,
accuracy_examples.png, accuracy_refinement.png.

Usage: accuracy.py [--quick] [--only CASE[,CASE...]]
"""
from __future__ import annotations

import argparse
import csv
import json
import math
import os
import shutil
import subprocess
import sys
import time
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
SGBEM = ROOT / "target" / "release" / "sgbem"
GMSH = os.environ.get("GMSH", "gmsh")
OUT = ROOT / "out" / "accuracy"
WORK = OUT / "runs"
QUADRATURES = ("fast", "standard", "accurate")
COLOURS = {"fast": "tab:orange", "standard": "tab:blue", "accurate": "tab:green"}
TARGETS = (1e-2, 1e-3)
META: dict = {}         # what was measured (the build), for the report

# Repeats: runs shorter than REPEAT_BELOW seconds are repeated REPEATS times (the machine
# is shared: the minimum is the least disturbed); very short ones more often.
REPEAT_BELOW = 3.0
REPEATS = 3
REPEATS_SHORT = 5
SHORT = 0.5


# ---------------------------------------------------------------------------------------
# Exact solutions (tests/exact/mod.rs; the scene headers give the same numbers).

def polar_stress(srr, stt, srt, th):
    s, c = np.sin(th), np.cos(th)
    return (srr * c * c + stt * s * s - 2 * srt * s * c,
            srr * s * s + stt * c * c + 2 * srt * s * c,
            (srr - stt) * s * c + srt * (c * c - s * s))


def polar_displacement(ur, ut, th):
    s, c = np.sin(th), np.cos(th)
    return ur * c - ut * s, ur * s + ut * c


class Ring:
    """Lamé ring a < r < b, plane strain, pressures p_in on r = a and p_out on r = b."""

    def __init__(self, a, b, p_in, p_out, young, poisson):
        self.a, self.b, self.p_in, self.p_out = a, b, p_in, p_out
        self.young, self.poisson = young, poisson
        a2, b2 = a * a, b * b
        self.A = (p_in * a2 - p_out * b2) / (b2 - a2)
        self.B = (p_in - p_out) * a2 * b2 / (b2 - a2)

    def ur(self, r):
        two_mu = self.young / (1 + self.poisson)
        return ((1 - 2 * self.poisson) * self.A * r + self.B / r) / two_mu

    def field(self, x, y):
        r, th = np.hypot(x, y), np.arctan2(y, x)
        u = polar_displacement(self.ur(r), 0.0 * r, th)
        s = polar_stress(self.A - self.B / r**2, self.A + self.B / r**2, 0.0 * r, th)
        return np.array(u), np.array(s)


class Lame:
    def __init__(self):
        self.ring = Ring(0.5, 1.0, 10.0, 0.0, 1000.0, 0.3)

    def field(self, x, y):
        return self.ring.field(x, y)

    def distance(self, x, y):
        r = np.hypot(x, y)
        return np.minimum.reduce([r - 0.5, 1.0 - r, x, y])


class Compound:
    """Inner ring 0.5 < r < 0.75 (E = 1000) bonded to 0.75 < r < 1 (E = 3000), nu = 0.3."""

    def __init__(self, a=0.5, c=0.75, b=1.0, p_in=10.0, young=(1000.0, 3000.0), nu=0.3):
        self.c = c

        def rings(pc):
            return (Ring(a, c, p_in, pc, young[0], nu), Ring(c, b, pc, 0.0, young[1], nu))

        def jump(pc):
            i, o = rings(pc)
            return i.ur(c) - o.ur(c)

        j0, j1 = jump(0.0), jump(1.0)
        self.pc = -j0 / (j1 - j0)
        assert abs(self.pc - 105 / 23) < 1e-12, self.pc
        self.inner, self.outer = rings(self.pc)

    def field(self, x, y):
        ui, si = self.inner.field(x, y)
        uo, so = self.outer.field(x, y)
        inner = np.hypot(x, y) < self.c
        return np.where(inner, ui, uo), np.where(inner, si, so)

    def distance(self, x, y):
        r = np.hypot(x, y)
        return np.minimum.reduce([r - 0.5, 1.0 - r, np.abs(r - self.c), x, y])


class Kirsch:
    """Quarter plate [0, 1]^2 minus r < 0.2, remote sigma_xx = 10, plane strain."""

    a, w, S, young, nu = 0.2, 1.0, 10.0, 1000.0, 0.3

    def field(self, x, y):
        a, S = self.a, self.S
        mu = self.young / (2 * (1 + self.nu))
        kappa = 3 - 4 * self.nu
        r, th = np.hypot(x, y), np.arctan2(y, x)
        a2, a4 = a * a, a**4
        ur = S / (4 * mu) * (r * (kappa - 1) / 2 + a2 / r
                             + (r + (kappa + 1) * a2 / r - a4 / r**3) * np.cos(2 * th))
        ut = -S / (4 * mu) * (r + (kappa - 1) * a2 / r + a4 / r**3) * np.sin(2 * th)
        q2 = (a / r) ** 2
        q4 = q2 * q2
        c2, s2 = np.cos(2 * th), np.sin(2 * th)
        srr = S / 2 * (1 - q2) + S / 2 * (1 - 4 * q2 + 3 * q4) * c2
        stt = S / 2 * (1 + q2) - S / 2 * (1 + 3 * q4) * c2
        srt = -S / 2 * (1 + 2 * q2 - 3 * q4) * s2
        return np.array(polar_displacement(ur, ut, th)), np.array(polar_stress(srr, stt, srt, th))

    def distance(self, x, y):
        r = np.hypot(x, y)
        return np.minimum.reduce([r - self.a, self.w - x, self.w - y, x, y])


class Cantilever:
    """Timoshenko-Goodier cantilever [0, 1] x [-0.1, 0.1], end load P = 0.01, plane stress."""

    L, c, P, E, nu = 1.0, 0.1, 0.01, 1000.0, 0.25

    def field(self, x, y):
        L, c, P, E, nu = self.L, self.c, self.P, self.E, self.nu
        inertia = 2 * c**3 / 3
        G = E / (2 * (1 + nu))
        u = (-P * x * x * y / (2 * E * inertia) - nu * P * y**3 / (6 * E * inertia)
             + P * y**3 / (6 * inertia * G)
             + (P * L * L / (2 * E * inertia) - P * c * c / (2 * inertia * G)) * y)
        v = (nu * P * x * y * y / (2 * E * inertia) + P * x**3 / (6 * E * inertia)
             - P * L * L * x / (2 * E * inertia) + P * L**3 / (3 * E * inertia))
        sxx = -P * x * y / inertia
        sxy = -P * (c * c - y * y) / (2 * inertia)
        return np.array([u, v]), np.array([sxx, 0.0 * x, sxy])

    def distance(self, x, y):
        return np.minimum.reduce([x, self.L - x, self.c - np.abs(y)])


class Column:
    """Column [-0.25, 0.25] x [0, 1] under its weight gamma = 10, plane strain."""

    w, H, gamma, E, nu = 0.5, 1.0, 10.0, 1000.0, 0.3

    def field(self, x, y):
        mu = self.E / (2 * (1 + self.nu))
        nu, g, d = self.nu, self.gamma, y - self.H
        u = np.array([-nu * g * d * x / (2 * mu),
                      (1 - nu) * g * d * d / (4 * mu) + nu * g * x * x / (4 * mu)])
        return u, np.array([0.0 * x, g * d, 0.0 * x])

    def distance(self, x, y):
        return np.minimum.reduce([self.w / 2 - np.abs(x), y, self.H - y])


# ---------------------------------------------------------------------------------------
# The cases.

@dataclass
class Level:
    label: str          # e.g. "n=32" or "f=0.71"
    h: float            # element size (benchmarks: 1/n; examples: factor on the paper's mesh)
    gmsh: list[str]     # -setnumber arguments


@dataclass
class Case:
    name: str
    scene: str
    geo: str
    levels: list[Level]
    exact: object = None
    interior: float = 0.0
    interface: str | None = None
    paper: float | None = None
    paper_note: str = ""
    h_label: str = "h = 1/n"
    front: bool = False     # the front estimate applies (a smooth contact edge)
    quantum: dict = field(default_factory=dict)   # level label -> joint element length


def n_levels(ns):
    return [Level(f"n={n}", 1.0 / n, ["-setnumber", "n", str(n)]) for n in ns]


FACTORS = (2.0, 1.41, 1.0, 0.71, 0.5)


def example1_levels(factors):
    # Paper mesh: h = 2 cm outside, h_joint = 0.1 cm on the 10 cm interface (100 pairs - 1).
    return [Level(f"f={f:g}", f, ["-setnumber", "h", f"{2.0 * f:.6g}",
                                  "-setnumber", "h_joint", f"{0.1 * f:.6g}"]) for f in factors]


def example2_levels(factors):
    # Paper mesh: h = 4 cm outside, 104 elements on the 40 cm joint.
    return [Level(f"f={f:g}", f, ["-setnumber", "h", f"{4.0 * f:.6g}",
                                  "-setnumber", "n_joint", str(round(104 / f))])
            for f in factors]


def cases(quick: bool) -> list[Case]:
    if quick:
        return [
            Case("lame_cylinder", "lame_cylinder", "lame_cylinder", n_levels([8, 16, 32]),
                 Lame(), 0.1),
            Case("example2", "clamped_beam_joint", "clamped_beam_joint",
                 example2_levels((2.0, 1.41, 1.0)), interface="joint", paper=33.85,
                 paper_note="33.85 cm (LCP)", h_label="f (x the paper's mesh)", front=True),
        ]
    ex = dict(interface="support", paper=8.4, h_label="f (x the paper's mesh)",
              paper_note="8.4 cm (LCP, no sliding)")
    return [
        Case("lame_cylinder", "lame_cylinder", "lame_cylinder",
             n_levels([8, 16, 32, 64, 128]), Lame(), 0.1),
        Case("compound_cylinder", "compound_cylinder", "compound_cylinder",
             n_levels([8, 16, 32, 64, 128]), Compound(), 0.05),
        Case("kirsch_plate", "kirsch_plate", "kirsch_plate",
             n_levels([6, 12, 24, 48, 96]), Kirsch(), 0.1),
        Case("timoshenko_cantilever", "timoshenko_cantilever", "timoshenko_cantilever",
             n_levels([20, 40, 80, 160, 320]), Cantilever(), 0.05),
        Case("self_weight_column", "self_weight_column", "self_weight_column",
             n_levels([8, 16, 32, 64, 128]), Column(), 0.1),
        Case("example1_stick", "beam_on_blocks", "beam_on_blocks", example1_levels(FACTORS),
             **ex),
        Case("example1_slide", "beam_on_blocks_slide", "beam_on_blocks",
             example1_levels(FACTORS), **ex),
        Case("example2", "clamped_beam_joint", "clamped_beam_joint", example2_levels(FACTORS),
             interface="joint", paper=33.85, paper_note="33.85 cm (LCP)",
             h_label="f (x the paper's mesh)", front=True),
    ]


# ---------------------------------------------------------------------------------------
# Scenes, meshes, runs.

def scene_sets(case: Case, quadrature: str) -> tuple[Path, list[str], list[str]]:
    """The pipeline's scene as it is, the `--set` overrides that give the study's outputs
    and quadrature (validated by sgbem like the file), and the names of its sections. The
    mesh and the output folder come from --mesh and --out."""
    path = ROOT / "pipelines" / f"{case.scene}.toml"
    sets = ["output.history=final", "output.field=false", "output.vtk=false",
            "output.operators=false", f"solve.quadrature={quadrature}"]
    parsed = tomllib.loads(path.read_text())
    sections = [s["name"] for s in parsed.get("output", {}).get("section", [])]
    return path, sets, sections


def mesh(case: Case, level: Level) -> Path:
    path = WORK / case.name / f"{level.label.replace('=', '')}.msh"
    path.parent.mkdir(parents=True, exist_ok=True)
    cmd = [GMSH, "-2", "-format", "msh41", *level.gmsh, str(ROOT / "geo" / f"{case.geo}.geo"),
           "-o", str(path)]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0 or not path.exists():
        sys.exit(f"accuracy: gmsh failed on {case.geo} {level.label}: {p.stderr or p.stdout}")
    return path


@dataclass
class Run:
    summary: dict
    seconds: float      # min of timings.total over the repeats
    wall: float         # min wall-clock time of the process
    repeats: int
    code: int
    notes: str
    out: Path


def run(scene: Path, sets: list[str], msh: Path, out: Path) -> Run:
    times, walls, notes, code, summary = [], [], "", 0, {}
    while True:
        if out.exists():
            shutil.rmtree(out)
        t0 = time.perf_counter()
        p = subprocess.run([str(SGBEM), "run", str(scene), "--mesh", str(msh), "--out",
                            str(out), "--quiet", *(a for x in sets for a in ("--set", x))],
                           capture_output=True, text=True)
        walls.append(time.perf_counter() - t0)
        code = p.returncode
        if code == 2 or (code != 0 and not (out / "summary.json").exists()):
            sys.exit(f"accuracy: sgbem run {scene} --mesh {msh} failed ({code}): {p.stderr}")
        this = json.loads((out / "summary.json").read_text())
        this["timings"] = json.loads((out / "timings.json").read_text())["stages"]
        times.append(this["timings"]["total"])
        if times[-1] == min(times):
            summary = this          # the stage timings of the fastest repeat
        notes = " ".join(l.strip() for l in p.stderr.splitlines() if l.strip())
        n_max = (1 if times[0] >= REPEAT_BELOW else
                 REPEATS_SHORT if times[0] < SHORT else REPEATS)
        if len(times) >= n_max or code != 0:
            break
    return Run(summary, min(times), min(walls), len(times), code, notes, out)


def read_section(path: Path) -> np.ndarray:
    with open(path) as f:
        rows = list(csv.DictReader(f))
    cols = ["x", "y", "ux", "uy", "sxx", "syy", "sxy"]
    return np.array([[float(r[c]) for c in cols] for r in rows])


def field_errors(case: Case, out: Path, sections: list[str]) -> dict:
    data = np.vstack([read_section(out / "sections" / f"{s}.csv") for s in sections])
    x, y = data[:, 0], data[:, 1]
    u, s = case.exact.field(x, y)
    u_ref = np.max(np.hypot(u[0], u[1]))
    s_ref = np.max(np.abs(s))
    eu = np.hypot(data[:, 2] - u[0], data[:, 3] - u[1]) / u_ref
    es = np.max(np.abs(data[:, 4:7].T - s), axis=0) / s_ref
    inner = case.exact.distance(x, y) >= case.interior
    return dict(error_u=eu.max(), error_sigma=es.max(),
                error_u_interior=eu[inner].max(), error_sigma_interior=es[inner].max(),
                points=len(x), interior_points=int(inner.sum()))


def front_estimate(path: Path, detached: float) -> float:
    """The detached length with the front placed inside its element. At each boundary
    between an open and a closed pair, opening^(2/3) (linear in the distance to a smooth
    contact edge, where the opening grows as d^(3/2)) of the two open pairs nearest to the
    front with a positive opening is extrapolated to zero; the front is clipped to lie
    between the nearer of them and the first closed pair. The detached length (measured by
    sgbem between the extreme open pairs) is moved by the front's offset from the last open
    pair."""
    with open(path) as f:
        rows = sorted(csv.DictReader(f), key=lambda r: float(r["s"]))
    s = np.array([float(r["s"]) for r in rows])
    g = np.array([float(r["normal_opening"]) for r in rows])
    is_open = np.array([r["status"] == "open" for r in rows])
    shift = 0.0
    for i in range(len(rows) - 1):
        if is_open[i] == is_open[i + 1]:
            continue
        o, c = (i, i + 1) if is_open[i] else (i + 1, i)
        away = o - c                           # the step from the front into the open zone
        found = []
        k = o
        while 0 <= k < len(rows) and is_open[k] and len(found) < 2:
            if g[k] > 0:
                found.append(k)
            k += away
        if len(found) < 2 or g[found[1]] <= g[found[0]]:
            continue
        p1, p2 = found
        a, b = g[p2] ** (2 / 3), g[p1] ** (2 / 3)
        front = s[p1] + (s[p1] - s[p2]) * b / (a - b)
        lo, hi = sorted((s[p1], s[c]))
        front = min(max(front, lo), hi)
        shift += (front - s[o]) * (s[c] - s[o]) / abs(s[c] - s[o])
    return detached + shift


# ---------------------------------------------------------------------------------------
# Analysis.

def slope(x, y) -> float:
    x, y = np.asarray(x, float), np.asarray(y, float)
    ok = (x > 0) & (y > 0) & np.isfinite(x) & np.isfinite(y)
    if ok.sum() < 2:
        return math.nan
    return float(np.polyfit(np.log(x[ok]), np.log(y[ok]), 1)[0])


def rate(x, y) -> str:
    v = slope(x, y)
    return f"{v:.2f}" if math.isfinite(v) else "–"


def fmt(v, digits=2) -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "–"
    if isinstance(v, str):
        return v
    if v == 0:
        return "0"
    return f"{v:.{digits}e}"


def secs(v) -> str:
    return f"{v:.3f}" if v < 1 else f"{v:.2f}"


def cheapest(rows, key, target):
    ok = [r for r in rows if r.get(key) is not None
          and math.isfinite(r[key]) and r[key] <= target]
    return min(ok, key=lambda r: r["seconds"]) if ok else None


def cheapest_example(mine, key, target, resolved):
    """Cheapest setting of an example whose `key` change is within `target`; with
    `resolved`, only levels whose interface element is itself within `target` of the
    length (a detached length is a whole number of elements)."""
    ok = [r for r in mine if not r["reference"] and r[key] <= target
          and (not resolved or r["quantum"] / r["detached_length"] <= target)]
    return min(ok, key=lambda r: r["seconds"]) if ok else None


def example_cell(mine, key, target) -> str:
    best = cheapest_example(mine, key, target, False)
    if best is None:
        return "none tried"
    text = describe(best)
    q = best["quantum"] / best["detached_length"]
    if q > target:
        good = cheapest_example(mine, key, target, True)
        text += (f", but one element there is {100 * q:.2g} % of the length; with elements "
                 f"≤ {100 * target:g} %: " + (describe(good) if good else "none tried"))
    return text


def describe(r) -> str:
    return f"{r['level']} {r['quadrature']} ({secs(r['seconds'])} s, {r['elements']} elements)"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="a small subset (a smoke test)")
    ap.add_argument("--only", help="comma-separated case names")
    ap.add_argument("--report-only", action="store_true",
                    help="redo the tables and plots from the last run's rows.json")
    args = ap.parse_args()
    if not SGBEM.exists():
        sys.exit(f"accuracy: {SGBEM} missing: make build")
    started = time.perf_counter()
    all_cases = cases(args.quick)
    if args.only:
        keep = set(args.only.split(","))
        all_cases = [c for c in all_cases if c.name in keep]
    OUT.mkdir(parents=True, exist_ok=True)

    if args.report_only:
        saved = json.loads((OUT / "rows.json").read_text())
        names = {r["case"] for r in saved["rows"]}
        META.update(saved.get("meta", {}))
        report([c for c in all_cases if c.name in names], saved["rows"], saved["elapsed"])
        return

    git = subprocess.run(["git", "-C", str(ROOT), "describe", "--always", "--dirty"],
                         capture_output=True, text=True).stdout.strip()
    META["build"] = (f"{SGBEM.relative_to(ROOT)} built "
                     f"{time.strftime('%Y-%m-%d %H:%M', time.localtime(SGBEM.stat().st_mtime))}"
                     f" from the working tree at {git or 'unknown commit'}")
    rows: list[dict] = []
    for case in all_cases:
        scenes = {q: scene_sets(case, q) for q in QUADRATURES}
        for level in case.levels:
            msh = mesh(case, level)
            for q in QUADRATURES:
                scene, sets, sections = scenes[q]
                out = WORK / case.name / f"{level.label.replace('=', '')}_{q}"
                r = run(scene, sets, msh, out)
                counts = r.summary.get("counts", {})
                row = dict(case=case.name, level=level.label, h=level.h,
                           elements=counts.get("boundary_elements", 0), quadrature=q,
                           seconds=r.seconds, wall=r.wall, repeats=r.repeats,
                           status=r.summary.get("status", f"exit {r.code}"), notes=r.notes)
                if case.exact is not None:
                    row.update(field_errors(case, out, sections))
                    show = f"u {row['error_u']:.2e}  sigma {row['error_sigma']:.2e}"
                else:
                    iface = r.summary["interfaces"][case.interface]
                    qp = r.summary.get("qp", {}).get("interfaces", {}).get(case.interface, {})
                    row.update(
                        detached_length=iface["detached_length"],
                        detached_qp=qp.get("detached_length"),
                        pairs=iface["pairs"],
                        contact_iterations=r.summary.get("contact", {}).get("iterations"),
                        front_estimate=front_estimate(
                            out / "interfaces" / f"{case.interface}.csv",
                            iface["detached_length"]) if case.front else math.nan)
                    show = (f"detached {row['detached_length']:.4f}  "
                            f"front {row['front_estimate']:.4f}")
                t = r.summary.get("timings", {})
                row.update(t_assemble=t.get("assemble", 0.0), t_condense=t.get("condense", 0.0),
                           t_contact=sum(v for k, v in t.items() if k.startswith("contact")),
                           t_postprocess=t.get("postprocess", 0.0))
                rows.append(row)
                print(f"accuracy: {case.name:22} {level.label:7} {q:8} "
                      f"{row['elements']:5} el  {show}  {r.seconds:7.3f} s"
                      f" (min of {r.repeats})" + ("  [note]" if r.notes else ""), flush=True)

    elapsed = time.perf_counter() - started
    (OUT / "rows.json").write_text(json.dumps({"elapsed": elapsed, "meta": META, "rows": rows},
                                              indent=0))
    report(all_cases, rows, elapsed)


def derive(all_cases, rows):
    """Examples: changes against the finest level run with `accurate`, and the paper."""
    def change(a, b):
        c = abs(a - b) / abs(b)
        return 0.0 if c < 1e-6 else c      # the same mesh's result, other quadrature

    for case in all_cases:
        if case.exact is not None:
            continue
        mine = [r for r in rows if r["case"] == case.name]
        ref = next(r for r in mine if r["level"] == case.levels[-1].label
                   and r["quadrature"] == "accurate")
        for r in mine:
            r["reference"] = r is ref
            r["change_vs_finest"] = change(r["detached_length"], ref["detached_length"])
            r["front_change_vs_finest"] = (change(r["front_estimate"], ref["front_estimate"])
                                           if case.front else math.nan)
            r["change_vs_paper"] = abs(r["detached_length"] - case.paper) / case.paper
            r["quantum"] = case_quantum(case, r)


def report(all_cases, rows, elapsed):
    derive(all_cases, rows)
    write_csv(rows)
    plot_benchmarks(all_cases, rows)
    plot_examples(all_cases, rows)
    plot_refinement(all_cases, rows)
    write_markdown(all_cases, rows, elapsed)
    print(f"accuracy: {len(rows)} settings in {elapsed:.0f} s; wrote {OUT.relative_to(ROOT)}/"
          "accuracy.csv, accuracy.md, accuracy_benchmarks.png, accuracy_examples.png, "
          "accuracy_refinement.png")


def case_quantum(case: Case, row: dict) -> float:
    """Length of one interface element at the row's level (the resolution of a detached
    length measured in whole elements)."""
    length = 40.0 if case.interface == "joint" else 10.0
    return length / (row["pairs"] - 1)


CSV_COLUMNS = ["case", "level", "h", "elements", "quadrature", "error_u", "error_sigma",
               "error_u_interior", "error_sigma_interior", "detached_length", "detached_qp",
               "front_estimate", "change_vs_finest", "front_change_vs_finest",
               "change_vs_paper", "quantum", "seconds", "wall", "repeats", "t_assemble",
               "t_condense", "t_contact", "t_postprocess", "status", "notes"]


def write_csv(rows):
    with open(OUT / "accuracy.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=CSV_COLUMNS, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v)
                        for k, v in r.items()})


def panel_grid(n, width=4.3, height=3.7, columns=3):
    rows = math.ceil(n / columns)
    fig, axes = plt.subplots(rows, columns, figsize=(width * columns, height * rows),
                             squeeze=False)
    return fig, [ax for line in axes for ax in line]


def no_minor_labels(ax):
    ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    ax.yaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())


def plot_benchmarks(all_cases, rows):
    bench = [c for c in all_cases if c.exact is not None]
    if not bench:
        return
    fig, axes = panel_grid(len(bench) + 1)
    for ax, case in zip(axes, bench):
        for q in QUADRATURES:
            rs = [r for r in rows if r["case"] == case.name and r["quadrature"] == q]
            t = [r["seconds"] for r in rs]
            ax.loglog(t, [r["error_sigma"] for r in rs], "o-", color=COLOURS[q],
                      label=f"{q}: stress")
            ax.loglog(t, [r["error_u"] for r in rs], "s--", color=COLOURS[q], mfc="none",
                      label=f"{q}: displacement")
        for r in rows:
            if r["case"] == case.name and r["quadrature"] == "standard":
                ax.annotate(r["level"], (r["seconds"], r["error_sigma"]), fontsize=7,
                            textcoords="offset points", xytext=(4, 4))
        for tgt in TARGETS:
            ax.axhline(tgt, color="grey", lw=0.8, ls=":")
        ax.set_title(case.name, fontsize=10)
        ax.set_xlabel("run time, s (timings.total)")
        ax.set_ylabel("relative max error")
        ax.grid(True, which="both", alpha=0.3)
        no_minor_labels(ax)
    axes[0].legend(fontsize=7)
    # The last panel: what each quadrature costs, all benchmarks together.
    ax = axes[len(bench)]
    for q in QUADRATURES:
        rs = [r for r in rows if r["quadrature"] == q and r.get("error_u") is not None]
        ax.loglog([r["elements"] for r in rs], [r["seconds"] for r in rs], "o",
                  color=COLOURS[q], label=q, alpha=0.8)
    ax.set_title("run time against boundary elements (all benchmarks)", fontsize=10)
    ax.set_xlabel("boundary elements")
    ax.set_ylabel("run time, s")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    no_minor_labels(ax)
    for ax in axes[len(bench) + 1:]:
        ax.axis("off")
    fig.suptitle("Closed-form benchmarks: error at the section points against run time "
                 "(dotted: 1 % and 0.1 %; labels: standard)")
    fig.tight_layout()
    fig.savefig(OUT / "accuracy_benchmarks.png", dpi=100)
    plt.close(fig)


def plot_examples(all_cases, rows):
    ex = [c for c in all_cases if c.exact is None]
    if not ex:
        return
    fig, axs = plt.subplots(2, len(ex), figsize=(4.6 * len(ex), 7.6), squeeze=False)
    for k, case in enumerate(ex):
        top, bottom = axs[0][k], axs[1][k]
        mine = [r for r in rows if r["case"] == case.name]
        changes = [r["change_vs_finest"] for r in mine] + \
            [r["front_change_vs_finest"] for r in mine]
        floor = 0.5 * min([c for c in changes if c > 0] + [1e-3])
        for q in QUADRATURES:
            rs = [r for r in mine if r["quadrature"] == q and not r["reference"]]
            t = np.array([r["seconds"] for r in rs])
            e = np.array([r["change_vs_finest"] for r in rs])
            top.loglog(t, np.where(e > 0, e, floor), "o-", color=COLOURS[q],
                       label=f"{q}: detached length")
            top.loglog(t[e == 0], np.full((e == 0).sum(), floor), "kx", ms=9)
            if case.front:
                fe = np.array([r["front_change_vs_finest"] for r in rs])
                top.loglog(t, np.where(fe > 0, fe, floor), "s--", color=COLOURS[q],
                           mfc="none", label=f"{q}: front estimate")
            rs = [r for r in mine if r["quadrature"] == q]
            bottom.semilogx([r["seconds"] for r in rs], [r["detached_length"] for r in rs],
                            "o-", color=COLOURS[q], label=f"{q}: detached length")
            if case.front:
                bottom.semilogx([r["seconds"] for r in rs], [r["front_estimate"] for r in rs],
                                "s--", color=COLOURS[q], mfc="none",
                                label=f"{q}: front estimate")
        for r in mine:
            if r["quadrature"] == "standard":
                bottom.annotate(r["level"], (r["seconds"], r["detached_length"]), fontsize=7,
                                textcoords="offset points", xytext=(4, -10))
        for tgt in TARGETS:
            top.axhline(tgt, color="grey", lw=0.8, ls=":")
        top.axhline(floor, color="k", lw=0.5)
        top.set_title(f"{case.name}: change against the finest run", fontsize=9)
        top.set_xlabel("run time, s")
        top.set_ylabel("relative change (x: none)")
        top.grid(True, which="both", alpha=0.3)
        no_minor_labels(top)
        bottom.axhline(case.paper, color="k", lw=1, ls="-.", label=f"paper: {case.paper} cm")
        bottom.set_title(f"{case.name}: detached length", fontsize=9)
        bottom.set_xlabel("run time, s")
        bottom.set_ylabel("cm")
        bottom.grid(True, which="both", alpha=0.3)
    from matplotlib.lines import Line2D
    handles = [Line2D([], [], color=COLOURS[q], lw=2, label=q) for q in QUADRATURES] + [
        Line2D([], [], color="k", marker="o", label="detached length (sgbem)"),
        Line2D([], [], color="k", marker="s", mfc="none", ls="--",
               label="front estimate (example 2)"),
        Line2D([], [], color="k", ls="-.", label="paper"),
        Line2D([], [], color="k", marker="x", ls="none", label="no change")]
    axs[1][0].legend(handles=handles, fontsize=7, loc="center right")
    fig.suptitle("Examples: detached length against run time (dotted: 1 % and 0.1 %; "
                 "x on the bottom line: the same length as the finest run)")
    fig.tight_layout()
    fig.savefig(OUT / "accuracy_examples.png", dpi=100)
    plt.close(fig)


def plot_refinement(all_cases, rows):
    """Error against element size (the convergence rates)."""
    bench = [c for c in all_cases if c.exact is not None]
    if not bench:
        return
    fig, axes = panel_grid(len(bench))
    for ax, case in zip(axes, bench):
        for q in QUADRATURES:
            rs = [r for r in rows if r["case"] == case.name and r["quadrature"] == q]
            h = [r["h"] for r in rs]
            ax.loglog(h, [r["error_sigma"] for r in rs], "o-", color=COLOURS[q],
                      label=f"{q}: stress")
            ax.loglog(h, [r["error_u"] for r in rs], "s--", color=COLOURS[q], mfc="none",
                      label=f"{q}: displacement")
            ax.loglog(h, [r["error_sigma_interior"] for r in rs], ":", color=COLOURS[q],
                      label=f"{q}: stress, interior points")
        h = np.array([r["h"] for r in rows if r["case"] == case.name])
        e0 = min(r["error_u"] for r in rows if r["case"] == case.name)
        ax.loglog([h.min(), h.max()], [e0, e0 * (h.max() / h.min()) ** 2], color="k", lw=0.6,
                  label="slope 2")
        for tgt in TARGETS:
            ax.axhline(tgt, color="grey", lw=0.8, ls=":")
        ax.set_title(case.name, fontsize=10)
        ax.set_xlabel("h = 1/n")
        ax.set_ylabel("relative max error")
        ax.grid(True, which="both", alpha=0.3)
        no_minor_labels(ax)
    axes[0].legend(fontsize=6)
    for ax in axes[len(bench):]:
        ax.axis("off")
    fig.suptitle("Closed-form benchmarks: error against element size")
    fig.tight_layout()
    fig.savefig(OUT / "accuracy_refinement.png", dpi=100)
    plt.close(fig)


def ratio(rows, q, base="standard"):
    """Median over the levels of the time of quadrature q over that of `base`."""
    by = {}
    for r in rows:
        by.setdefault((r["case"], r["level"]), {})[r["quadrature"]] = r["seconds"]
    v = [d[q] / d[base] for d in by.values() if q in d and base in d and d[base] > 0]
    return float(np.median(v)) if v else math.nan


def spread(mine, key, where=False):
    """Largest relative difference of `key` between the quadratures at one level (and the
    level, with `where`)."""
    worst, at = 0.0, None
    for level in dict.fromkeys(r["level"] for r in mine):
        v = [r[key] for r in mine if r["level"] == level]
        if min(v) > 0 and (max(v) - min(v)) / min(v) > worst:
            worst, at = (max(v) - min(v)) / min(v), level
    return (worst, at) if where else worst


def write_markdown(all_cases, rows, elapsed):
    bench = [c for c in all_cases if c.exact is not None]
    ex = [c for c in all_cases if c.exact is None]
    for r in rows:
        if r.get("error_u") is not None:
            r["error_both"] = max(r["error_u"], r["error_sigma"])
    md = ["# Accuracy against run time", "",
          "Written by `make accuracy` (`pipelines/accuracy.py`); every number is in "
          "`accuracy.csv`. Times are `stages.total` of timings.json, the minimum over "
          f"{REPEATS} repeats for runs under {REPEAT_BELOW:g} s ({REPEATS_SHORT} under "
          f"{SHORT:g} s), on a shared 2-core machine (other jobs ran too: times of a few "
          "hundredths of a second are mostly noise). Each run writes only what the study "
          "reads (no interior field, no VTK, no archived operators, final history only), so "
          "the times are those of reading, assembly, condensation, solve and sections.", "",
          "Benchmarks: relative maximum errors over every section point, as "
          "tests/convergence.rs measures them (*u*: max |u_h − u| / max |u|; *σ*: "
          "max_c |σ_h,c − σ_c| / max_c |σ_c|; the section points come down to 0.01–0.02 "
          "from a boundary). A setting *reaches* a target when both are below it. Examples: "
          "the relative change of the detached length (LCP) against the finest level run "
          "with `accurate` (itself left out of the search).", ""]

    md += ["## Cheapest settings", "",
           "| case | largest mesh (elements) | 1 % | 0.1 % |", "|---|---|---|---|"]
    for case in bench + ex:
        mine = [r for r in rows if r["case"] == case.name]
        cells = []
        for tgt in TARGETS:
            if case.exact is not None:
                best = cheapest(mine, "error_both", tgt)
                cells.append(describe(best) if best else "none tried")
            else:
                cells.append(example_cell(mine, "change_vs_finest", tgt))
        md.append(f"| {case.name} | {max(r['elements'] for r in mine)} | {cells[0]} | "
                  f"{cells[1]} |")
    bench_rows = [r for r in rows if r.get("error_u") is not None]
    md += ["", f"Time relative to `standard` (median over all settings): fast "
           f"{ratio(rows, 'fast'):.2f}×, accurate {ratio(rows, 'accurate'):.2f}×."]
    if bench_rows:
        spreads = sorted(((*spread([r for r in bench_rows if r["case"] == c.name], k, True),
                           c.name, k) for c in bench for k in ("error_u", "error_sigma")),
                         reverse=True)
        value, level, name, key = spreads[0]
        at = {r["quadrature"]: r[key] for r in bench_rows
              if r["case"] == name and r["level"] == level}
        others = max(v[0] for v in spreads if v[2] != name)
        md.append(f"Between the quadratures at one level, the benchmarks' errors differ by at "
                  f"most {100 * value:.2g} % of themselves ({name}, "
                  f"{'u' if key == 'error_u' else 'σ'} at {level}: "
                  + ", ".join(f"{q} {fmt(at[q])}" for q in QUADRATURES)
                  + f"), in the other cases by less than {100 * others:.2g} %: the element "
                  "size, not the quadrature, sets the error.")
    md.append("")

    for case in bench:
        mine = [r for r in rows if r["case"] == case.name]
        md += [f"## {case.name}", ""]
        head = "| level | elements |" + "".join(
            f" {q}: u | {q}: σ | {q}: s |" for q in QUADRATURES)
        md += [head, "|---|---|" + "---|" * (3 * len(QUADRATURES))]
        for level in case.levels:
            rs = {r["quadrature"]: r for r in mine if r["level"] == level.label}
            md.append(f"| {level.label} | {rs['standard']['elements']} |" + "".join(
                f" {fmt(rs[q]['error_u'])} | {fmt(rs[q]['error_sigma'])} | "
                f"{secs(rs[q]['seconds'])} |" for q in QUADRATURES))
        md += ["", "Fitted log-log slopes (least squares over the levels) of the error "
               "against h = 1/n and against the run time, and of the time against the "
               "elements. *Interior*: the section points at least "
               f"{case.interior:g} from every curve.", "",
               "| quadrature | u vs h | σ vs h | interior u vs h | interior σ vs h | "
               "u vs time | σ vs time | time vs elements |",
               "|---|---|---|---|---|---|---|---|"]
        for q in QUADRATURES:
            rs = [r for r in mine if r["quadrature"] == q]
            h = [r["h"] for r in rs]
            t = [r["seconds"] for r in rs]
            md.append(
                f"| {q} | {rate(h, [r['error_u'] for r in rs])} | "
                f"{rate(h, [r['error_sigma'] for r in rs])} | "
                f"{rate(h, [r['error_u_interior'] for r in rs])} | "
                f"{rate(h, [r['error_sigma_interior'] for r in rs])} | "
                f"{rate(t, [r['error_u'] for r in rs])} | "
                f"{rate(t, [r['error_sigma'] for r in rs])} | "
                f"{rate([r['elements'] for r in rs], t)} |")
        md += ["", f"The quadratures' errors differ by at most "
               f"{100 * spread(mine, 'error_u'):.2g} % (u) and "
               f"{100 * spread(mine, 'error_sigma'):.2g} % (σ) of each other at one level.",
               "", sentence(case, mine), ""]

    for case in ex:
        mine = [r for r in rows if r["case"] == case.name]
        ref = next(r for r in mine if r["reference"])
        front = (f"; front estimate {ref['front_estimate']:.4f} cm" if case.front else "")
        md += [f"## {case.name}", "",
               f"Reference: {ref['level']} accurate, detached length "
               f"{ref['detached_length']:.4f} cm ({ref['pairs']} pairs, one interface "
               f"element = {ref['quantum']:.4f} cm){front}; paper {case.paper_note}. Level f "
               "scales every element size of the paper's mesh (f=1).", "",
               "| level | elements | pairs | one element (cm) |" + "".join(
                   f" {q}: detached (cm) | {q}: s |" for q in QUADRATURES)
               + (" front estimate (cm) |" if case.front else "")
               + " change vs finest | vs paper | contact share of the time |",
               "|---|---|---|---|" + "---|" * (2 * len(QUADRATURES))
               + ("---|" if case.front else "") + "---|---|---|"]
        for level in case.levels:
            rs = {r["quadrature"]: r for r in mine if r["level"] == level.label}
            s = rs["standard"]
            md.append(f"| {level.label} | {s['elements']} | {s['pairs']} | "
                      f"{s['quantum']:.4f} |" + "".join(
                          f" {rs[q]['detached_length']:.4f} | {secs(rs[q]['seconds'])} |"
                          for q in QUADRATURES)
                      + (f" {s['front_estimate']:.4f} |" if case.front else "")
                      + f" {fmt(s['change_vs_finest'])} | "
                      f"{100 * (s['detached_length'] / case.paper - 1):+.1f} % | "
                      f"{100 * s['t_contact'] / s['seconds']:.0f} % |")
        md += ["", "(changes, front estimate and contact share: standard quadrature; the "
               "contact share is the LCP, active-set and QP solvers' part of "
               "`timings.total`.)", "",
               "| quadrature | change vs h | change vs time | time vs pairs |"
               + (" front-estimate change vs h |" if case.front else ""),
               "|---|---|---|---|" + ("---|" if case.front else "")]
        for q in QUADRATURES:
            rs = [r for r in mine if r["quadrature"] == q
                  and r["level"] != case.levels[-1].label]
            h = [r["h"] for r in rs]
            t = [r["seconds"] for r in rs]
            all_q = [r for r in mine if r["quadrature"] == q]
            md.append(f"| {q} | {rate(h, [r['change_vs_finest'] for r in rs])} | "
                      f"{rate(t, [r['change_vs_finest'] for r in rs])} | "
                      f"{rate([r['pairs'] for r in all_q], [r['seconds'] for r in all_q])}"
                      " |" + (f" {rate(h, [r['front_change_vs_finest'] for r in rs])} |"
                              if case.front else ""))
        differ = [r for r in mine if r["detached_qp"] is not None
                  and abs(r["detached_qp"] - r["detached_length"]) > 1e-9]
        noted = [r for r in mine if r["notes"]]
        same = all(len({r["detached_length"] for r in mine if r["level"] == lv.label}) == 1
                   for lv in case.levels)
        md += ["", "Slopes fitted over the levels coarser than the finest; a change of 0 "
               "(the same number of detached elements) is left out of a fit. The detached "
               "length is a whole number of interface elements, so a change smaller than one "
               "element (column *one element*) is below the resolution of the mesh.", ""]
        if same:
            md.append("The three quadratures give the same detached length at every level.")
        md.append(sentence(case, mine))
        if differ:
            md.append("QP and LCP detached lengths differ in: " + ", ".join(
                f"{r['level']} {r['quadrature']} (QP {r['detached_qp']:.4f})" for r in differ)
                + ".")
        if noted:
            md += ["", "sgbem notes (stderr):", ""]
            for note in dict.fromkeys(r["notes"] for r in noted):
                where = ", ".join(f"{r['level']} {r['quadrature']}" for r in noted
                                  if r["notes"] == note)
                md.append(f"- {where}: {note}")
        md.append("")

    largest = max(rows, key=lambda r: r["elements"])
    md += ["## Run", "",
           f"{META.get('build', '')}.", "",
           f"{len(rows)} settings in {elapsed:.0f} s (including repeats and meshing); the "
           f"largest mesh: {largest['case']} {largest['level']}, {largest['elements']} "
           "boundary elements.", "",
           "Plots: `accuracy_benchmarks.png` (error against time), `accuracy_refinement.png` "
           "(error against h), `accuracy_examples.png` (detached length against time).", ""]
    (OUT / "accuracy.md").write_text("\n".join(md))


def sentence(case, mine) -> str:
    parts = []
    for tgt in TARGETS:
        pct = f"{100 * tgt:g} %"
        if case.exact is not None:
            best = cheapest(mine, "error_both", tgt)
            u = cheapest(mine, "error_u", tgt)
            if best:
                text = f"{pct} in u and σ: {describe(best)}"
                if u and u is not best:
                    text += f" (u alone: {describe(u)})"
            elif u:
                text = f"{pct}: none of those tried in σ; u alone: {describe(u)}"
            else:
                text = f"{pct}: none of those tried"
        else:
            text = (f"{pct} of the finest: {example_cell(mine, 'change_vs_finest', tgt)}; "
                    f"within {pct} of the paper ({case.paper} cm): "
                    f"{example_cell(mine, 'change_vs_paper', tgt)}")
        parts.append(text)
    return f"**Cheapest**, {case.name}: " + "; ".join(parts) + "."


if __name__ == "__main__":
    main()
