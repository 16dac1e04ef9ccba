"""Pictures of the thrust line (run by `make report`): the blocks of a run's final state,
their joints coloured by contact status, and the thrust line through the joints' points of
application, each point labelled with its eccentricity |e| / (L/2) (1: at the joint's edge,
a hinge); a body with more than two loaded joints (a brick in a bond) has a hub, drawn as a
square, and lines from its joints' points to it (docs/thrust.md). With more than 40 joints
only the points at a joint's edge (|e| / (L/2) > 0.99) are labelled.

  docs/img/thrust_arch.png: out/arch (20 voussoirs under self-weight, t/R = 0.12);
  docs/img/thrust_wall.png: out/wall (a pier of 8 blocks under self-weight and wind);
  docs/img/thrust_wall_running_bond.png: out/wall_running_bond (105 bricks in running bond
  under self-weight and wind: the force paths through the bricks' hubs).

Reads the run's last VTK state (vtk/boundary_NNNN.vtu and vtk/thrust_NNNN.vtu, meshio),
thrust.csv and, where there is one, thrust_hubs.csv (its hubs must be the VTK block's); the
geometry is the undeformed one (the points of application are on it). A run folder missing
under OUT is skipped. Usage: thrust_plots.py OUT IMG [RUN ...]
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
    wide = 12 if len(rows) > 40 else 9
    fig, ax = plt.subplots(figsize=(wide, float(np.clip(6.5 * wide / 9 * h / w, 4.5, 8.0))))
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
    hub = thrust.point_data["joint"].ravel() < 0
    many = len(rows) > 40
    lw = 1.2 if many else 2.2
    for block in thrust.cells:
        if block.type == "line":
            for a, b in block.data:
                ax.plot(p[[a, b], 0], p[[a, b], 1], color="tab:blue", lw=lw, zorder=3)
    ax.plot(p[~hub, 0], p[~hub, 1], "o", color="tab:blue", ms=3 if many else 5, zorder=4)
    ax.plot(p[hub, 0], p[hub, 1], "s", color="navy", ms=3 if many else 5, zorder=4)
    ratio = thrust.point_data["e_over_half_length"].ravel()
    for (x, y), r, h in zip(p, ratio, hub):
        if not h and (not many or abs(r) > 0.99):
            ax.annotate(f"{abs(r):.2f}", (x, y), xytext=(4, 4), textcoords="offset points",
                        fontsize=6 if many else 7, color="tab:blue")
    hubs = check_hubs(run, p[hub])
    n = [float(r[3]) for r in rows if r[5]]  # the joints that carry a point
    joint_ratio = np.abs(ratio[~hub])
    hinges = int(np.sum(joint_ratio > 0.999))
    ax.plot([], [], color="tab:green", lw=2, label="joint closed")
    ax.plot([], [], color="tab:red", lw=2, label="joint open")
    labels = "|e| / (L/2) > 0.99" if many else "|e| / (L/2)"
    ax.plot([], [], "o-", color="tab:blue", label=f"thrust line (labels: {labels})")
    if hubs:
        ax.plot([], [], "s", color="navy", label="hub of a body with more joints")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)
    ax.set_aspect("equal")
    ax.margins(0.04)
    ax.set_xlabel("x"), ax.set_ylabel("y")
    with_hubs = f", {hubs} hubs" if hubs else ""
    ax.set_title(f"{run.name}: thrust line of the final state, {len(rows)} joints{with_hubs}, "
                 f"N from {min(n):.3g} to {max(n):.3g} {unit}, {hinges} at a joint's edge "
                 f"(hinge)", fontsize=9)
    fig.tight_layout()
    fig.savefig(png, dpi=130)
    plt.close(fig)
    print(f"thrust_plots: {png}: {len(rows)} joints, {hubs} hubs, "
          f"max |e|/(L/2) {joint_ratio.max():.3f}")
    return True


def check_hubs(run, points):
    """The number of hubs; those of thrust_hubs.csv must be the VTK block's `points`."""
    path = run / "thrust_hubs.csv"
    if not path.exists():
        return len(points)
    with open(path) as f:
        rows = list(csv.reader(f))[1:]
    listed = np.array([[float(r[1]), float(r[2])] for r in rows]).reshape(-1, 2)
    drawn = np.asarray(points).reshape(-1, 2)
    same = len(listed) == len(drawn) and all(
        np.any(np.all(drawn == q, axis=1)) for q in listed)
    if not same:
        sys.exit(f"thrust_plots: {path}: its {len(listed)} hubs are not the VTK block's "
                 f"{len(drawn)}")
    return len(listed)


def main():
    out, img = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
    runs = sys.argv[3:] or ["arch", "wall", "wall_running_bond"]
    for name in runs:
        run = out / name
        if not (run / "thrust.csv").exists():
            print(f"thrust_plots: {run}: no thrust.csv (not run, or no joints): skipped")
            continue
        draw(run, img / f"thrust_{name}.png")


main()
