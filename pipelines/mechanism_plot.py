"""The mechanism of a run as a picture: every body's boundary in grey, the moving bodies
in orange, drawn displaced along their rigid motion, and the centres of their rotations.

Reads RUN/vtk/mechanism_NNNN.vtu (the block written in the final state of a run that failed
at a mechanism, or of a collapse search: `mechanism_velocity`, normalised to 1 at the
fastest boundary node), the boundary of the same state and RUN/summary.json (the motion and,
for a collapse search, the multiplier bracket).

Usage: mechanism_plot.py RUN OUT.png [--scale S] [--title TEXT]
  S: the displacement drawn for the fastest node, as a fraction of the model's size
     (default 0.04).
Needs meshio and matplotlib (the project's .venv).
"""
import argparse
import json
import pathlib
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import meshio  # noqa: E402
import numpy as np  # noqa: E402


def last(folder, stem):
    files = sorted(folder.glob(f"{stem}_*.vtu"))
    return files[-1] if files else None


def segments(mesh):
    lines = np.concatenate([c.data for c in mesh.cells if c.type == "line"])
    return mesh.points[:, :2], lines


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run")
    ap.add_argument("out")
    ap.add_argument("--scale", type=float, default=0.04)
    ap.add_argument("--title", default=None)
    a = ap.parse_args()
    run = pathlib.Path(a.run)
    vtk = run / "vtk"
    mech_file = last(vtk, "mechanism")
    if mech_file is None:
        sys.exit(f"{a.run}: no vtk/mechanism_*.vtu (the run found no mechanism)")
    summary = json.loads((run / "summary.json").read_text())
    collapse = (summary.get("contact") or {}).get("collapse") or {}
    motion = collapse.get("motion") or summary.get("mechanism") or []
    bnd_pts, bnd_lines = segments(meshio.read(last(vtk, "boundary")))
    mech = meshio.read(mech_file)
    m_pts, m_lines = segments(mech)
    vel = mech.point_data["mechanism_velocity"][:, :2]
    size = np.ptp(bnd_pts, axis=0).max()
    moving = np.linalg.norm(vel, axis=1) > 1e-9
    shift = a.scale * size * vel
    fig, ax = plt.subplots(figsize=(10, 5.6))
    for p, q in bnd_lines:
        ax.plot(*bnd_pts[[p, q]].T, color="0.6", lw=0.5)
    for p, q in m_lines:
        if moving[p] or moving[q]:
            ax.plot(*(m_pts[[p, q]] + shift[[p, q]]).T, color="tab:orange", lw=1.0)
    centres = [m["centre"] for m in motion if m.get("kind") == "rotation" and "centre" in m]
    if centres:
        c = np.array(centres)
        ax.plot(c[:, 0], c[:, 1], "k+", ms=12, mew=1.5, label="centres of rotation")
        ax.legend(loc="upper left")
    ax.set_aspect("equal")
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    title = a.title
    if title is None:
        title = summary.get("title", run.name)
        if collapse:
            title += (f"\ncollapse multiplier {collapse['multiplier']:.4g} "
                      f"(collapses at {collapse.get('collapses_at')}); "
                      f"{len(motion)} bodies move")
    ax.set_title(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(a.out, dpi=130)
    print(f"{a.out}: {int(moving.sum())} moving boundary nodes, {len(motion)} bodies")


if __name__ == "__main__":
    main()
