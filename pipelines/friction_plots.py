"""Pictures of the friction examples for the README (run by `make report`).

  docs/img/cattaneo_mindlin_traction.png: pressure and tangential traction along the contact
      of out/cattaneo_mindlin (normal load P, then Q = 0.5 mu P) beside Johnson's Hertz and
      Cattaneo-Mindlin distributions for the run's own P and Q, stick and slip pairs marked;
  docs/img/beam_on_blocks_friction_support.png: the support of example 1 with mu = 0.6:
      normal and tangential traction, stick / slip / open pairs.
A run folder missing under out/ is skipped.
Usage: friction_plots.py OUT IMG
"""
import csv
import json
import math
import pathlib
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def rows(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def cattaneo_mindlin(out, img):
    run = out / "cattaneo_mindlin"
    if not (run / "summary.json").exists():
        print(f"friction_plots: {run} missing (make examples): skipped")
        return
    s = json.loads((run / "summary.json").read_text())
    f = s["interfaces"]["contact"]
    p_load = -f["normal_resultant"]
    q_load = abs(f["tangential_resultant"])
    mu, radius = 0.5, 100.0
    e_star = 1000.0 / (2.0 * (1.0 - 0.3 ** 2))
    a = math.sqrt(4.0 * p_load * radius / (math.pi * e_star))
    p0 = 2.0 * p_load / (math.pi * a)
    c = a * math.sqrt(1.0 - q_load / (mu * p_load))
    r = [x for x in rows(run / "interfaces" / "contact.csv") if abs(float(x["x"])) <= 1.3 * a]
    x = [float(v["x"]) for v in r]
    p = [-float(v["normal_traction"]) for v in r]
    q = [float(v["tangential_traction"]) for v in r]
    sign = 1.0 if sum(q) > 0 else -1.0
    q = [sign * v for v in q]
    xs = [a * (-1.0 + 2.0 * k / 400) for k in range(401)]
    hertz = [p0 * math.sqrt(max(0.0, 1 - t * t / (a * a))) for t in xs]
    cm = [mu * p0 * (math.sqrt(max(0.0, 1 - t * t / (a * a)))
                     - (c / a) * math.sqrt(max(0.0, 1 - t * t / (c * c)))) for t in xs]
    fig, ax = plt.subplots(figsize=(8, 4.2))
    ax.plot(xs, hertz, "k-", lw=1, label="Hertz p(x)")
    ax.plot(xs, [mu * v for v in hertz], "k:", lw=1, label="μ p(x)")
    ax.plot(xs, cm, "k--", lw=1, label="Cattaneo–Mindlin q(x)")
    ax.plot(x, p, "o", ms=3, color="tab:blue", label="sgbem pressure")
    for status, colour in (("stick", "tab:green"), ("slip", "tab:red")):
        pts = [(xi, qi) for xi, qi, v in zip(x, q, r) if v["tangential_status"] == status]
        if pts:
            ax.plot(*zip(*pts), "s", ms=3, color=colour, label=f"sgbem q, {status}")
    ax.axvspan(-c, c, color="tab:green", alpha=0.08)
    ax.set_xlabel("x")
    ax.set_ylabel("traction")
    ax.set_title(f"Cattaneo–Mindlin: Q/(μP) = {q_load / (mu * p_load):.2f}, "
                 f"c/a = {c / a:.3f} (shaded: Johnson's stick zone)")
    ax.legend(fontsize=8, loc="upper right")
    fig.tight_layout()
    fig.savefig(img / "cattaneo_mindlin_traction.png", dpi=110)
    print(f"friction_plots: {img / 'cattaneo_mindlin_traction.png'}")


def beam_support(out, img):
    run = out / "beam_on_blocks_friction"
    if not (run / "summary.json").exists():
        print(f"friction_plots: {run} missing (make examples): skipped")
        return
    r = rows(run / "interfaces" / "support.csv")
    r.sort(key=lambda v: float(v["x"]))
    x = [float(v["x"]) for v in r]
    fig, ax = plt.subplots(figsize=(8, 3.6))
    ax.plot(x, [float(v["normal_traction"]) for v in r], "-", color="tab:blue",
            label="normal traction (tension +)")
    ax.plot(x, [float(v["tangential_traction"]) for v in r], "-", color="tab:orange",
            label="tangential traction")
    colours = {"stick": "tab:green", "slip": "tab:red", "open": "0.6"}
    for status, colour in colours.items():
        pts = [xi for xi, v in zip(x, r) if v["tangential_status"] == status]
        if pts:
            ax.plot(pts, [0.0] * len(pts), "|", ms=14, color=colour, label=status)
    ax.set_xlabel("x (cm)")
    ax.set_ylabel("daN/cm²")
    ax.set_title("Example 1 with μ = 0.6: the beam's support (stick / slip / open)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(img / "beam_on_blocks_friction_support.png", dpi=110)
    print(f"friction_plots: {img / 'beam_on_blocks_friction_support.png'}")


def main():
    out, img = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
    img.mkdir(parents=True, exist_ok=True)
    cattaneo_mindlin(out, img)
    beam_support(out, img)


if __name__ == "__main__":
    main()
