"""Pictures of the thrust line (run by `make report`): the blocks of a run's final state,
their joints coloured by contact status, and the thrust line through the joints' points of
application, each point labelled with its eccentricity |e| / (L/2) (1: at the joint's edge,
a hinge).

  docs/img/thrust_arch.png: out/arch (20 voussoirs under self-weight, t/R = 0.12);
  docs/img/thrust_wall.png: out/wall (a pier of 8 blocks under self-weight and wind).

Reads the run's last VTK state (vtk/boundary_NNNN.vtu and vtk/thrust_NNNN.vtu, meshio) and
thrust.csv; the geometry is the undeformed one (the points of application are on it). A run
folder missing under OUT is skipped. Usage: thrust_plots.py OUT IMG [RUN ...]
"""
import csv
import pathlib
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import meshio  # noqa: E402
import numpy as np  # noqa: E402

STATUS = {1: ("closed", "tab:green"), 0: ("open", "tab:red")}


def last(run, prefix):
    files = sorted((run / "vtk").glob(f"{prefix}_*.vtu"))
    return meshio.read(files[-1]) if files else None


def draw(run, png):
    boundary, thrust = last(run, "boundary"), last(run, "thrust")
    if boundary is None or thrust is None:
        print(f"thrust_plots: {run}: no VTK boundary or thrust files (output.vtk = false?)")
        return False
    with open(run / "thrust.csv") as f:
        rows = list(csv.reader(f))
    header, rows = rows[0], rows[1:]
    unit = header[3].split("[")[-1].rstrip("]")
    pts = boundary.points[:, :2]
    w, h = np.ptp(pts, axis=0)
    fig, ax = plt.subplots(figsize=(9, float(np.clip(6.5 * h / w, 4.5, 8.0))))
    status = boundary.point_data["contact_status"]
    for block in boundary.cells:
        if block.type != "line":
            continue
        for a, b in block.data:
            s = (status[a], status[b])
            name, colour = STATUS.get(min(s), (None, "black"))
            joint = s[0] >= 0 and s[1] >= 0
            ax.plot(pts[[a, b], 0], pts[[a, b], 1], color=colour if joint else "black",
                    lw=2.0 if joint else 0.8, solid_capstyle="butt")
    p = thrust.points[:, :2]
    for block in thrust.cells:
        if block.type == "line":
            for a, b in block.data:
                ax.plot(p[[a, b], 0], p[[a, b], 1], color="tab:blue", lw=2.2, zorder=3)
    ax.plot(p[:, 0], p[:, 1], "o", color="tab:blue", ms=5, zorder=4)
    ratio = thrust.point_data["e_over_half_length"]
    for (x, y), r in zip(p, ratio):
        ax.annotate(f"{abs(r):.2f}", (x, y), xytext=(4, 4), textcoords="offset points",
                    fontsize=7, color="tab:blue")
    n = [float(r[3]) for r in rows if r[3]]
    hinges = sum(1 for r in ratio if abs(r) > 0.999)
    ax.plot([], [], color="tab:green", lw=2, label="joint closed")
    ax.plot([], [], color="tab:red", lw=2, label="joint open")
    ax.plot([], [], "o-", color="tab:blue", label="thrust line (labels: |e| / (L/2))")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)
    ax.set_aspect("equal")
    ax.margins(0.04)
    ax.set_xlabel("x"), ax.set_ylabel("y")
    ax.set_title(f"{run.name}: thrust line of the final state, {len(rows)} joints, N from "
                 f"{min(n):.3g} to {max(n):.3g} {unit}, {hinges} at a joint's edge (hinge)",
                 fontsize=9)
    fig.tight_layout()
    fig.savefig(png, dpi=130)
    plt.close(fig)
    print(f"thrust_plots: {png}: {len(rows)} joints, max |e|/(L/2) {abs(ratio).max():.3f}")
    return True


def main():
    out, img = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
    runs = sys.argv[3:] or ["arch", "wall"]
    for name in runs:
        run = out / name
        if not (run / "thrust.csv").exists():
            print(f"thrust_plots: {run}: no thrust.csv (not run, or no joints): skipped")
            continue
        draw(run, img / f"thrust_{name}.png")


main()
