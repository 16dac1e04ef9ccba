#!/usr/bin/env python3
"""The paper's example 3 (depressed vault on two piers): our results beside its Tables 3 and 4.

Reads OUT/vault/sweep/cohesion=<c in daN/cm², one decimal>/summary.json (and
sections/s<k>.csv when present), the folders of the cohesion sweep c = 0.4, 0.3, 0.2, 0.1,
0 MPa made by `make vault` (`sgbem sweep pipelines/vault_c0.toml --set
'interface.*.cohesion=4.0,3.0,2.0,1.0,0.0'`), and writes

  OUT/vault/table3.md  detached length (cm) per section group 1-5, 2-4, 3 for every cohesion
  OUT/vault/table4.md  largest compressive stress (MPa) per group for c = 0.4 and c = 0

each beside the paper's values. Usage: vault_table.py [OUT]  (default: out)

Stresses: the scenes are in cm and daN, so stresses are in daN/cm²; 1 MPa = 10 daN/cm².
"On the joint" is the most negative nodal normal traction on the joint (summary.json,
interfaces.<s>.min_normal_traction); "near the joint" is the most negative hoop stress
(normal to the radial section) on the section 2.5 cm from the joint (sections/<s>.csv).
Standard library only.
"""

import csv
import json
import math
import os
import sys

COHESIONS = ["0.4", "0.3", "0.2", "0.1", "0"]  # MPa
GROUPS = [("1-5", ["s1", "s5"]), ("2-4", ["s2", "s4"]), ("3", ["s3"])]

# The paper's Table 3: detachment lengths (cm) by iterative LCP.
PAPER_T3 = {
    "1-5": {"0.4": 0.0, "0.3": 35.29, "0.2": 35.29, "0.1": 35.29, "0": 35.29},
    "2-4": {"0.4": 0.0, "0.3": 0.0, "0.2": 0.0, "0.1": 0.0, "0": 11.76},
    "3": {"0.4": 0.0, "0.3": 0.0, "0.2": 0.0, "0.1": 38.24, "0": 38.24},
}
# The paper's Table 4: maximum (compressive) stress values (MPa).
PAPER_T4 = {
    "1-5": {"0.4": -0.39674, "0": -0.49140},
    "2-4": {"0.4": -0.16843, "0": -0.16372},
    "3": {"0.4": -0.20383, "0": -0.33641},
}
DAN_CM2_PER_MPA = 10.0
JOINT_ELEMENT = 50.0 / 17.0  # cm: every joint is 50 cm deep with 17 elements


def run_dir(out, c):
    """The sweep folder of cohesion c (MPa, text): named from the swept value in daN/cm²."""
    return os.path.join(out, "vault", "sweep", f"cohesion={float(c) * DAN_CM2_PER_MPA:.1f}")


def load(out, c):
    """The summary of one run, or None if it is missing."""
    path = os.path.join(run_dir(out, c), "summary.json")
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


def load_timings(out, c):
    """The stage timings of one run (timings.json), or {} if missing."""
    try:
        with open(os.path.join(run_dir(out, c), "timings.json")) as f:
            return json.load(f).get("stages", {})
    except (OSError, ValueError):
        return {}


def section_min_hoop(out, c, name):
    """Most negative hoop stress (daN/cm²) on a radial section, or None."""
    path = os.path.join(run_dir(out, c), "sections", f"{name}.csv")
    try:
        with open(path, newline="") as f:
            rows = [r for r in csv.DictReader(f)]
    except OSError:
        return None
    pts = [(float(r["x"]), float(r["y"])) for r in rows]
    if len(pts) < 2:
        return None
    dx, dy = pts[-1][0] - pts[0][0], pts[-1][1] - pts[0][1]
    n = math.hypot(dx, dy)
    tx, ty = -dy / n, dx / n  # the hoop direction: normal to the radial section
    best = None
    for r in rows:
        sxx, syy, sxy = float(r["sxx"]), float(r["syy"]), float(r["sxy"])
        if any(math.isnan(v) for v in (sxx, syy, sxy)):
            continue
        s = sxx * tx * tx + 2.0 * sxy * tx * ty + syy * ty * ty
        best = s if best is None else min(best, s)
    return best


def fmt_len(values):
    """One length, or 'a / b' when the two joints of a symmetric pair differ."""
    if max(values) - min(values) < 1e-6:
        return f"{values[0]:.2f}"
    return " / ".join(f"{v:.2f}" for v in values)


def fmt_mpa(values):
    if any(v is None for v in values):
        return "—"
    if max(values) - min(values) < 1e-9 * max(1.0, abs(min(values))):
        return f"{values[0]:.5f}"
    return " / ".join(f"{v:.5f}" for v in values)


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "out"
    runs = {c: load(out, c) for c in COHESIONS}
    missing = [c for c, s in runs.items() if s is None]
    dest = os.path.join(out, "vault")
    os.makedirs(dest, exist_ok=True)

    # ---- Table 3
    lines = [
        "# Example 3: detached length (cm) per section group, ours (paper)",
        "",
        "Iterative LCP with brittle cohesion; `ours` is sgbem on geo/vault.geo (our geometry:",
        "the paper draws its vault only in a figure). Where the two joints of a symmetric pair",
        "differ both are given (s1 / s5, s2 / s4). One joint element is "
        f"{JOINT_ELEMENT:.4f} cm (50 cm, 17 elements).",
        "",
        "| Sections | " + " | ".join(f"c = {c} MPa" for c in COHESIONS) + " |",
        "|---|" + "---|" * len(COHESIONS),
    ]
    for group, joints in GROUPS:
        cells = []
        for c in COHESIONS:
            s = runs[c]
            paper = f"{PAPER_T3[group][c]:.2f}"
            if s is None:
                cells.append(f"— ({paper})")
            else:
                ours = fmt_len([s["interfaces"][j]["detached_length"] for j in joints])
                cells.append(f"{ours} ({paper})")
        lines.append(f"| {group} | " + " | ".join(cells) + " |")
    # No run times in the table, so that a rerun writes the same file; they are printed.
    lines += ["", "| run | status | contact iterations |", "|---|---|---|"]
    for c in COHESIONS:
        s = runs[c]
        if s is None:
            lines.append(f"| c = {c} | missing | |")
            continue
        it = s.get("contact", {}).get("iterations", "")
        lines.append(f"| c = {c} | {s.get('status')} | {it} |")
        t = load_timings(out, c).get("total")
        if isinstance(t, (int, float)):
            print(f"vault c = {c}: {t:.2f} s (timings.json)")
    if missing:
        lines += ["", "Missing runs: " + ", ".join(run_dir(out, c) for c in missing)]
    with open(os.path.join(dest, "table3.md"), "w") as f:
        f.write("\n".join(lines) + "\n")

    # ---- Table 4
    lines = [
        "# Example 3: largest compressive stress (MPa) per section group",
        "",
        "On the joint: the most negative nodal normal traction on the joint (interfaces/<s>.csv).",
        "Near the joint: the most negative hoop stress on the radial section 2.5 cm from the",
        "joint (sections/<s>.csv). Paper: its Table 4. s1 / s5 (s2 / s4) given apart if they differ.",
        "",
        "| Sections | c = 0.4: on the joint | near the joint | paper "
        "| c = 0: on the joint | near the joint | paper |",
        "|---|---|---|---|---|---|---|",
    ]
    for group, joints in GROUPS:
        cells = []
        for c in ["0.4", "0"]:
            s = runs[c]
            if s is None:
                cells += ["—", "—"]
            else:
                on = [s["interfaces"][j]["min_normal_traction"] / DAN_CM2_PER_MPA for j in joints]
                near = [section_min_hoop(out, c, j) for j in joints]
                near = [None if v is None else v / DAN_CM2_PER_MPA for v in near]
                cells += [fmt_mpa(on), fmt_mpa(near)]
            cells.append(f"{PAPER_T4[group][c]:.5f}")
        lines.append(f"| {group} | " + " | ".join(cells) + " |")
    with open(os.path.join(dest, "table4.md"), "w") as f:
        f.write("\n".join(lines) + "\n")

    for name in ("table3.md", "table4.md"):
        print(f"vault_table: wrote {os.path.join(dest, name)}")
    if missing:
        print("vault_table: missing runs: " + ", ".join(missing), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
