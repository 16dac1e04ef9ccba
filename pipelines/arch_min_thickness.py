"""The minimum thickness of a semicircular masonry arch under its own weight, by bisection.

Runs pipelines/arch.toml (geo/arch.geo: radial joints, centre-line radius R = 5 m) with
`--set mesh.t=...` for ring thicknesses t between two bounds, with Coulomb friction high
enough that no joint slides (mu = 1 by default), and bisects on t/R between a ring that
stands (sgbem exits 0) and one that collapses (exit 3: "no equilibrium exists", the hinge
mechanism). Milankovitch's value for a continuous semicircular arch with radial joints is
t/R = 0.1075 (Heyman, Ochsendorf).

Usage: arch_min_thickness.py SGBEM [--voussoirs 40] [--lo 0.09] [--hi 0.13] [--tol 0.0005]
           [--mu 1.0] [--out out/arch_min]
Writes OUT/trials.csv (t/R, outcome, seconds) and OUT/result.md; prints the result.
"""
import argparse
import pathlib
import subprocess
import sys
import time

R = 5.0  # centre-line radius of geo/arch.geo's default


def trial(sgbem, t_over_r, args, out):
    folder = out / f"t{t_over_r:.5f}"
    cmd = [
        sgbem, "run", "pipelines/arch.toml",
        "--set", f"mesh.nv={args.voussoirs}",
        "--set", f"mesh.t={t_over_r * R:.6f}",
        "--set", "defaults.interface.tangential=friction",
        "--set", f"defaults.interface.friction={args.mu}",
        "--out", str(folder), "--quiet",
    ]
    t0 = time.time()
    p = subprocess.run(cmd, capture_output=True, text=True)
    seconds = time.time() - t0
    if p.returncode == 0:
        return "stands", seconds, ""
    if p.returncode == 3 and "no equilibrium exists" in p.stderr:
        return "collapses", seconds, p.stderr.strip()
    sys.exit(f"arch_min_thickness: t/R = {t_over_r}: exit {p.returncode}: {p.stderr.strip()}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("sgbem")
    ap.add_argument("--voussoirs", type=int, default=40)
    ap.add_argument("--lo", type=float, default=0.09)
    ap.add_argument("--hi", type=float, default=0.13)
    ap.add_argument("--tol", type=float, default=0.0005)
    ap.add_argument("--mu", type=float, default=1.0)
    ap.add_argument("--out", default="out/arch_min")
    args = ap.parse_args()
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    lo, hi = args.lo, args.hi
    for bound, want in ((lo, "collapses"), (hi, "stands")):
        outcome, s, _ = trial(args.sgbem, bound, args, out)
        rows.append((bound, outcome, s))
        if outcome != want:
            sys.exit(f"arch_min_thickness: t/R = {bound} {outcome}; widen --lo/--hi")
    mechanism = ""
    while hi - lo > args.tol:
        mid = 0.5 * (lo + hi)
        outcome, s, msg = trial(args.sgbem, mid, args, out)
        rows.append((mid, outcome, s))
        if outcome == "stands":
            hi = mid
        else:
            lo, mechanism = mid, msg
    found = 0.5 * (lo + hi)
    with open(out / "trials.csv", "w") as f:
        f.write("t_over_R,outcome,seconds\n")
        for r in rows:
            f.write(f"{r[0]:.6f},{r[1]},{r[2]:.2f}\n")
    text = (
        f"# Minimum thickness of a semicircular arch ({args.voussoirs} voussoirs, mu = {args.mu})\n\n"
        f"t/R = {found:.4f} (between {lo:.4f}, collapses, and {hi:.4f}, stands; "
        f"{len(rows)} runs); Milankovitch 0.1075: {100 * (found / 0.1075 - 1):+.1f} %\n\n"
        f"Mechanism just below: {mechanism or '(the lower bound)'}\n"
    )
    (out / "result.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
