"""Pictures of sgbem runs, off-screen: strained shapes, detachment histories, sections.

Usage: report.py RUN_DIR... [--out docs/img]

For each run folder (the output of `sgbem run`; a folder without summary.json is skipped
with a message) it writes, into the output folder, PNGs named after the folder:

  <run>_shape.png                  strained shape of every body in the final state, the
                                   displacements magnified by a factor chosen so the largest
                                   one is about 6 % of the model's size (printed in the title):
                                   the interior field of vtk/field_NNNN.vtu rendered by
                                   pyvista, coloured by sigma_xx and by von Mises, with the
                                   deformed boundary of the final state (black), of the first
                                   contact iteration (blue, dashed) and the undeformed outline
                                   (grey); without a field file, the deformed boundary lines of
                                   vtk/boundary_NNNN.vtu coloured by |u|;
  <run>_detachment.png             one row per interface: the normal opening along it (arc
                                   length s) for the contact iterations in /history of
                                   archive.h5, the status map iterations x s, and the detached
                                   length per iteration (with the QP's final value and the
                                   paper's, where known);
  <run>_sections.png               one row per section of sections/*.csv (final state): normal
                                   stresses and shear along it (x, y components for sections
                                   along an axis, else normal/along/shear to the section);
  <run>_sections_history.png       the normal stress on each section for five states of the
                                   contact iterations (for example 2 the paper's Fig. 6 at
                                   d = 0, 8.46, 16.92, 25.38, 33.85 cm);
  <run>_section_<name>_beam.png    for the paper's example 2: sigma_x and tau_xy at a-a against
                                   beam theory for the continuous clamped beam (the paper's
                                   Fig. 5; sign conventions in the picture).
The states' section stresses come from sgbem's sections/<name>_path.csv when the run wrote
it (history = "full"), checked at three states against Somigliana's identity evaluated here
from the archived boundary displacements and tractions (pipelines/somigliana.py); without
that file, from pipelines/somigliana.py alone, checked against sections/<name>.csv at the
final state. The check is printed and written on the picture.

Exit status 1 if a picture failed (the others are still made).
"""
import argparse
import csv
import json
import os
import pathlib
import sys
import traceback
import xml.etree.ElementTree as ET

os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")
os.environ.setdefault("MPLBACKEND", "Agg")

import h5py  # noqa: E402
import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import meshio  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import somigliana  # noqa: E402

# What the paper reports, by run folder name (Tables 1 and 2, Figs. 5 and 6).
PAPER = {
    "beam_on_blocks": {"detached": {"support": {"LCP": 8.4, "Vodicka": 8.3, "QP": 8.2}}},
    "beam_on_blocks_slide": {"detached": {"support": {"LCP": 8.4, "Vodicka": 8.3, "QP": 8.2}}},
    "clamped_beam_joint": {
        "detached": {"joint": {"LCP": 33.85, "QP": 33.08}},
        "fig6_d": [0.0, 8.46, 16.92, 25.38, 33.85],
        # continuous clamped-clamped beam: span L, depth h, width b, load q (force/length)
        "beam": {"q": 10.0, "L": 400.0, "h": 40.0, "b": 1.0},
    },
}

DPI = 110


def save(fig, name):
    """Save as a 256-colour PNG (a third of the size of the full-colour one, same look)."""
    import io
    from PIL import Image
    buf = io.BytesIO()
    fig.savefig(buf, dpi=DPI, format="png")
    plt.close(fig)
    buf.seek(0)
    img = Image.open(buf).convert("RGB")
    img.quantize(colors=256, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE).save(name, optimize=True)


def text(v):
    return v.decode() if isinstance(v, bytes) else str(v)


def suptitle(fig, msg, fontsize):
    """Figure title wrapped to the figure's width."""
    import textwrap
    width = max(40, int(fig.get_figwidth() * 125 / fontsize))
    lines = [w for line in msg.split("\n") for w in (textwrap.wrap(line, width) or [""])]
    fig.suptitle("\n".join(lines), fontsize=fontsize)


def vtk_iteration(mesh):
    """The contact iteration a VTK file holds (its field data `iteration`)."""
    return int(np.ravel(mesh.field_data["iteration"])[0])


def nice_factor(x):
    """Largest of 1, 2, 5 x 10^k not above x (at least 1e-12)."""
    if not np.isfinite(x) or x <= 0:
        return 1.0
    k = np.floor(np.log10(x))
    for m in (5.0, 2.0, 1.0):
        if m * 10 ** k <= x:
            return m * 10 ** k
    return 10 ** k


def fmt_factor(f):
    return f"{f:g}" if 1e-3 <= f < 1e6 else f"{f:.0e}"


class Run:
    def __init__(self, path):
        self.path = path
        self.name = path.name
        self.summary = json.loads((path / "summary.json").read_text())
        self.h5 = h5py.File(path / "archive.h5", "r") if (path / "archive.h5").exists() else None
        units = self.summary.get("units", {})
        self.ulen = units.get("length", "")
        self.uforce = units.get("force", "")
        self.ustress = f"{self.uforce}/{self.ulen}²" if self.ulen and self.uforce else ""
        self.title = self.summary.get("title", self.name)
        self.pvd = self._read_pvd()

    def close(self):
        if self.h5 is not None:
            self.h5.close()

    def _read_pvd(self):
        pvd = self.path / "vtk" / "history.pvd"
        out = {"boundary": [], "field": []}
        if not pvd.exists():
            return out
        for e in ET.parse(pvd).getroot().find("Collection").findall("DataSet"):
            f = e.get("file")
            kind = f.split("_")[0]
            if kind in out and (self.path / "vtk" / f).exists():
                out[kind].append((float(e.get("timestep")), self.path / "vtk" / f))
        return out

    def interfaces(self):
        if self.h5 is None or "interfaces" not in self.h5:
            return []
        return [text(n) for n in self.h5["interfaces"].attrs["order"]]

    def state_names(self):
        if self.h5 is None or "states" not in self.h5:
            return []
        return [f"{k:04d}" for k in range(int(self.h5["states"].attrs["count"]))]


# --------------------------------------------------------------------------------------
# strained shape
# --------------------------------------------------------------------------------------
def boundary_polylines(path, factor):
    """Deformed and undeformed segments (k,2,2) of a boundary_NNNN.vtu."""
    m = meshio.read(path)
    lines = np.vstack([c.data for c in m.cells if c.type == "line"]).astype(int)
    x = m.points[:, :2]
    u = m.point_data["displacement"][:, :2]
    return x[lines], (x + factor * u)[lines]


def render_field(grid, scalars, cmap, clim, box, width_px):
    """pyvista off-screen render of a 2D grid filling exactly the world box (x0,x1,y0,y1)."""
    import pyvista as pv
    pv.OFF_SCREEN = True
    x0, x1, y0, y1 = box
    w = int(width_px)
    h = max(40, int(round(w * (y1 - y0) / (x1 - x0))))
    p = pv.Plotter(off_screen=True, window_size=(w, h))
    p.set_background("white")
    p.add_mesh(grid, scalars=scalars, cmap=cmap, clim=clim, show_scalar_bar=False,
               lighting=False, interpolate_before_map=True)
    p.enable_parallel_projection()
    cam = p.camera
    cx, cy = 0.5 * (x0 + x1), 0.5 * (y0 + y1)
    cam.focal_point = (cx, cy, 0.0)
    cam.position = (cx, cy, 10.0 * max(x1 - x0, y1 - y0))
    cam.up = (0.0, 1.0, 0.0)
    cam.parallel_scale = 0.5 * (y1 - y0)
    p.reset_camera_clipping_range()
    img = p.screenshot(return_img=True)
    p.close()
    return img


def shape_picture(run, out):
    import pyvista as pv
    bnd = run.pvd["boundary"]
    fld = run.pvd["field"]
    if not bnd and not fld:
        print(f"report: {run.path}: no VTK files (output.vtk = false?): no shape picture")
        return []
    final_b = bnd[-1] if bnd else None
    final_f = fld[-1] if fld else None
    first_b = bnd[0] if len(bnd) > 1 else None

    # magnification from the final state's largest displacement and the model's size
    src = final_f[1] if final_f else final_b[1]
    m = meshio.read(src)
    x = m.points[:, :2]
    u = m.point_data["displacement"][:, :2]
    if final_b:
        mb = meshio.read(final_b[1])
        x = np.vstack([x, mb.points[:, :2]])
        u = np.vstack([u, mb.point_data["displacement"][:, :2]])
    size = float(np.max(x.max(0) - x.min(0)))
    umax = float(np.max(np.hypot(u[:, 0], u[:, 1])))
    factor = nice_factor(0.06 * size / umax) if umax > 0 else 1.0
    xd = x + factor * u
    lo = np.minimum(x.min(0), xd.min(0))
    hi = np.maximum(x.max(0), xd.max(0))
    pad = 0.04 * float(np.max(hi - lo))
    box = (lo[0] - pad, hi[0] + pad, lo[1] - pad, hi[1] + pad)
    aspect = (box[3] - box[2]) / (box[1] - box[0])

    # The pvd's times are load-step fractions; each file's field data names its iteration.
    iteration = vtk_iteration(m)
    when = f"final state (contact iteration {iteration})" if len(bnd) > 1 else "final state"
    head = (f"{run.title}\n{when}; displacements × {fmt_factor(factor)}"
            f" (largest |u| = {umax:.3g} {run.ulen})")

    overlays = []
    if final_b:
        x0s, xds = boundary_polylines(final_b[1], factor)
        overlays.append((x0s, dict(color="0.6", lw=0.8), "undeformed"))
        if first_b and first_b[1] != final_b[1]:
            _, x1s = boundary_polylines(first_b[1], factor)
            overlays.append((x1s, dict(color="tab:blue", lw=0.9, ls="--"),
                             f"iteration {vtk_iteration(meshio.read(first_b[1]))} (before any status change)"))
        overlays.append((xds, dict(color="k", lw=0.9), "final"))

    def draw_overlays(ax):
        from matplotlib.collections import LineCollection
        for segs, style, label in overlays:
            ax.add_collection(LineCollection(segs, label=label, **style))

    panel_w = 9.0
    panel_h = max(1.3, min(6.0, panel_w * aspect))
    if final_f:
        grid = pv.read(final_f[1])
        disp = np.asarray(grid.point_data["displacement"])
        grid.points = grid.points + factor * disp
        stress = np.asarray(grid.point_data["stress"])
        grid.point_data["sxx"] = stress[:, 0]
        vm = np.asarray(grid.point_data["von_mises"])
        sxx_clip = float(np.percentile(np.abs(stress[:, 0]), 99)) or 1.0
        vm_clip = float(np.percentile(vm, 99)) or 1.0
        panels = [
            ("sxx", "RdBu_r", (-sxx_clip, sxx_clip), f"σxx ({run.ustress})",
             f"σxx: colour range ±{sxx_clip:.3g} (99th percentile of |σxx|); extremes {stress[:, 0].min():.3g} … {stress[:, 0].max():.3g}"),
            ("von_mises", "viridis", (0.0, vm_clip), f"von Mises ({run.ustress})",
             f"von Mises: colour range 0 … {vm_clip:.3g} (99th percentile); largest {vm.max():.3g}"),
        ]
        if aspect > 0.45:   # compact models: panels side by side
            pw = min(6.0, 7.0 / aspect)
            ph = max(1.3, min(7.0, pw * aspect))
            fig, axes = plt.subplots(1, len(panels), figsize=(len(panels) * (pw + 1.6), ph + 2.2), squeeze=False)
            axes = axes.T
        else:               # slender models: panels stacked
            fig, axes = plt.subplots(len(panels), 1, figsize=(panel_w + 1.6, len(panels) * (panel_h + 0.9) + 0.9),
                                     squeeze=False)
        for ax, (key, cmap, clim, label, note) in zip(axes[:, 0], panels):
            img = render_field(grid, key, cmap, clim, box, 1200 if aspect < 1 else 1200 / aspect)
            ax.imshow(img, extent=box, origin="upper", interpolation="lanczos")
            draw_overlays(ax)
            ax.set_xlim(box[0], box[1])
            ax.set_ylim(box[2], box[3])
            ax.set_aspect("equal")
            ax.set_xlabel(f"x ({run.ulen})")
            ax.set_ylabel(f"y ({run.ulen})")
            ax.set_title(note, fontsize=8.5)
            sm = plt.cm.ScalarMappable(cmap=cmap, norm=plt.Normalize(*clim))
            fig.colorbar(sm, ax=ax, label=label, extend="both" if key == "sxx" else "max",
                         fraction=0.04, pad=0.02)
        handles, labels = axes[0, 0].get_legend_handles_labels()
        fig.legend(handles, labels, loc="lower center", ncol=3, fontsize=8, frameon=False)
        suptitle(fig, head + "\ninterior field from " + final_f[1].name, fontsize=10)
    else:
        fig, ax = plt.subplots(figsize=(panel_w + 1.6, panel_h + 1.6))
        from matplotlib.collections import LineCollection
        mb = meshio.read(final_b[1])
        lines = np.vstack([c.data for c in mb.cells if c.type == "line"]).astype(int)
        ub = mb.point_data["displacement"][:, :2]
        mag = np.hypot(ub[:, 0], ub[:, 1])[lines].mean(1)
        xs, xds = boundary_polylines(final_b[1], factor)
        ax.add_collection(LineCollection(xs, color="0.6", lw=0.8, label="undeformed"))
        lc = LineCollection(xds, array=mag, cmap="viridis", lw=2.5)
        ax.add_collection(lc)
        fig.colorbar(lc, ax=ax, label=f"|u| ({run.ulen})", fraction=0.04, pad=0.02)
        ax.set_xlim(box[0], box[1])
        ax.set_ylim(box[2], box[3])
        ax.set_aspect("equal")
        ax.set_xlabel(f"x ({run.ulen})")
        ax.set_ylabel(f"y ({run.ulen})")
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=3, fontsize=8, frameon=False)
        suptitle(fig, head + "\nno interior field (output.field = false): boundary from " + final_b[1].name,
                     fontsize=10)
    fig.tight_layout(rect=(0, 0.04, 1, 1))
    name = out / f"{run.name}_shape.png"
    save(fig, name)
    print(f"report: {name}: displacements × {fmt_factor(factor)}")
    return [name]


# --------------------------------------------------------------------------------------
# detachment along the interfaces
# --------------------------------------------------------------------------------------
MAX_DETACHMENT_ROWS = 8


def detachment_pictures(run, out):
    made = []
    h5 = run.h5
    if h5 is None or "history" not in h5 or "interfaces" not in h5["history"]:
        return made
    hist = h5["history"]
    rows = hist["load_factor"].shape[0]
    if rows == 0:
        return made
    iteration = hist["iteration"][()]
    step = hist["load_step"][()]
    dl_all = hist["detached_length"][()]
    paper = PAPER.get(run.name, {}).get("detached", {})
    names = run.interfaces()
    if not names:
        return made
    # Scenes of many joints (a wall of a hundred bricks has hundreds of interfaces): the
    # MAX_DETACHMENT_ROWS with the largest final detached length, in interface order.
    total = len(names)
    chosen = list(range(total))
    if total > MAX_DETACHMENT_ROWS:
        final = dl_all[-1]
        chosen = sorted(sorted(chosen, key=lambda k: (-final[k], k))[:MAX_DETACHMENT_ROWS])
    fig, grid = plt.subplots(len(chosen), 3, figsize=(15, 4.2 * len(chosen) + 0.6), squeeze=False,
                             gridspec_kw={"width_ratios": [1.25, 1.0, 1.0]})
    for axes, k in zip(grid, chosen):
        iname = names[k]
        g = hist["interfaces"][iname]
        status = g["status"][()]
        opening = g["normal_opening"][()]
        s = h5["interfaces"][iname]["s"][()]
        order = np.argsort(s)
        s, status, opening = s[order], status[:, order], opening[:, order]
        dl = dl_all[:, k]
        r = np.arange(rows)

        # zoom on the part of the interface where anything happens when that is small
        busy = np.flatnonzero((status == 1).any(0) | (status != status[:1]).any(0))
        zoom = None
        if busy.size and len(s) > 1:
            lo, hi = s[max(busy[0] - 1, 0)], s[min(busy[-1] + 1, len(s) - 1)]
            if hi - lo < 0.4 * (s[-1] - s[0]):
                pad = 0.25 * (hi - lo)
                zoom = (max(s[0], lo - pad), min(s[-1], hi + pad))
        ax = axes[0]
        cmap = plt.cm.viridis
        stride = max(1, rows // 40)
        shown = list(range(0, rows, stride))
        if shown[-1] != rows - 1:
            shown.append(rows - 1)
        norm = plt.Normalize(0, max(rows - 1, 1))
        for j in shown:
            last = j == rows - 1
            ax.plot(s, opening[j], color="k" if last else cmap(norm(j)), lw=1.6 if last else 0.8,
                    label=f"final (row {j})" if last else None, zorder=3 if last else 2)
        sm = plt.cm.ScalarMappable(cmap=cmap, norm=norm)
        fig.colorbar(sm, ax=ax, label="contact iteration (history row)", fraction=0.05, pad=0.02)
        ax.axhline(0, color="0.5", lw=0.6)
        ax.set_xlabel(f"arc length s along {iname} ({run.ulen})")
        ax.set_ylabel(f"normal opening ({run.ulen})")
        if zoom:
            inside = (s >= zoom[0]) & (s <= zoom[1])
            v = opening[:, inside]
            span = float(v.max() - v.min()) or 1.0
            ax.set_xlim(*zoom)
            ax.set_ylim(float(v.min()) - 0.05 * span, float(v.max()) + 0.05 * span)
        ax.legend(fontsize=7, loc="best")

        ax = axes[1]
        ds = np.diff(s)
        edges = np.concatenate([[s[0] - 0.5 * ds[0]], s[:-1] + 0.5 * ds, [s[-1] + 0.5 * ds[-1]]]) if len(s) > 1 \
            else np.array([s[0] - 0.5, s[0] + 0.5])
        redges = np.arange(rows + 1) - 0.5
        from matplotlib.colors import ListedColormap
        ax.pcolormesh(edges, redges, status, cmap=ListedColormap(["#f4a261", "#264653"]), vmin=0, vmax=1,
                      shading="flat")
        ax.set_xlabel(f"arc length s along {iname} ({run.ulen})")
        ax.set_ylabel("contact iteration (history row)")
        if zoom:
            ax.set_xlim(*zoom)
        ax.set_title("(b) status per pair: dark closed, orange open" + (" (zoomed)" if zoom else ""), fontsize=9)
        if len(np.unique(step)) > 1:
            for j in np.flatnonzero(np.diff(step)) + 0.5:
                ax.axhline(j, color="w", lw=0.8)

        ax = axes[2]
        ax.plot(r, dl, "-", color="tab:blue", lw=1.2, label="sgbem LCP (history)")
        ax.plot(r[-1], dl[-1], "o", color="tab:blue", ms=5)
        qp = run.summary.get("qp", {}).get("interfaces", {}).get(iname)
        if qp is not None:
            ax.axhline(qp["detached_length"], color="tab:orange", ls="-.", lw=1.0,
                       label=f"sgbem QP: {qp['detached_length']:.4g} {run.ulen}")
        styles = {"LCP": ("tab:green", "--"), "QP": ("tab:red", ":"), "Vodicka": ("tab:purple", (0, (5, 2, 1, 2)))}
        for method, value in paper.get(iname, {}).items():
            c, ls = styles.get(method, ("0.3", "--"))
            ax.axhline(value, color=c, ls=ls, lw=1.0, label=f"paper {method}: {value} {run.ulen}")
        ax.set_xlabel("contact iteration (history row)")
        ax.set_ylabel(f"detached length ({run.ulen})")
        ax.set_title(f"(c) detached length; final {dl[-1] + 0.0:.4g} {run.ulen} of "
                     f"{float(h5['interfaces'][iname].attrs.get('length', s[-1] - s[0])):.4g}", fontsize=9)
        ax.legend(fontsize=7, loc="best")
        ax.grid(alpha=0.3)
        first = text(h5["interfaces"][iname].attrs.get("body_a", "first body"))
        axes[0].set_title(f"{iname}: (a) normal opening per iteration" + (" (zoomed on the contact zone)" if zoom else "")
                          + (f" (one row in {stride})" if stride > 1 else ""), fontsize=9)
        axes[1].set_ylabel(f"contact iteration (history row)\n{iname}: s from its first node, normal out of {first}",
                           fontsize=8)
        print(f"report: {run.path}: interface {iname}: {rows} rows, final detached length {dl[-1] + 0.0:.4g}")
    steps = len(np.unique(step))
    shown_note = (f" (the {len(chosen)} of {total} interfaces with the largest final detached length)"
                  if len(chosen) < total else "")
    suptitle(fig, f"{run.title}: {total} interface{'s' if total > 1 else ''}{shown_note} over {rows} history rows "
                  f"(iterations {iteration[0]}…{iteration[-1]}{', load steps ' + str(steps) if steps > 1 else ''}); "
                  f"s = arc length from the interface curve's first node; opening = normal jump (positive open)",
             fontsize=9.5)
    fig.tight_layout(rect=(0, 0, 1, 1 - 0.5 / fig.get_figheight()))
    name = out / f"{run.name}_detachment.png"
    save(fig, name)
    print(f"report: {name}")
    made.append(name)
    return made


# --------------------------------------------------------------------------------------
# sections
# --------------------------------------------------------------------------------------
def read_section(path):
    rows = list(csv.DictReader(path.open()))
    cols = {k: np.array([float(r[k]) for r in rows]) for k in ["x", "y", "ux", "uy", "sxx", "syy", "sxy"]}
    return cols


def section_axis(sec):
    """Coordinate to plot along: y for a vertical section, x for a horizontal one, else distance."""
    dx = sec["x"][-1] - sec["x"][0]
    dy = sec["y"][-1] - sec["y"][0]
    if abs(dx) <= 1e-9 * (abs(dy) + 1e-300):
        return sec["y"], "y", True
    if abs(dy) <= 1e-9 * (abs(dx) + 1e-300):
        return sec["x"], "x", False
    return np.hypot(sec["x"] - sec["x"][0], sec["y"] - sec["y"][0]), "distance from start", False


def plot_along(ax, pos, vals, vertical, **kw):
    if vertical:
        ax.plot(vals, pos, **kw)
    else:
        ax.plot(pos, vals, **kw)


def label_axes(ax, vertical, poslabel, vallabel):
    if vertical:
        ax.set_xlabel(vallabel)
        ax.set_ylabel(poslabel)
        ax.axvline(0, color="0.5", lw=0.6)
    else:
        ax.set_xlabel(poslabel)
        ax.set_ylabel(vallabel)
        ax.axhline(0, color="0.5", lw=0.6)
    ax.grid(alpha=0.3)


def section_components(sec):
    """Stress components to draw for a section: ((values, label) normal, (values, label) shear, note)."""
    tx, ty = sec["x"][-1] - sec["x"][0], sec["y"][-1] - sec["y"][0]
    n = np.hypot(tx, ty) or 1.0
    tx, ty = tx / n, ty / n
    if abs(tx) < 1e-9:
        return (sec["sxx"], "σxx"), (sec["syy"], "σyy"), (sec["sxy"], "τxy"), "x, y components"
    if abs(ty) < 1e-9:
        return (sec["syy"], "σyy"), (sec["sxx"], "σxx"), (sec["sxy"], "τxy"), "x, y components"
    nx, ny = ty, -tx    # normal: the section's direction turned clockwise
    snn = sec["sxx"] * nx * nx + sec["syy"] * ny * ny + 2 * sec["sxy"] * nx * ny
    stt = sec["sxx"] * tx * tx + sec["syy"] * ty * ty + 2 * sec["sxy"] * tx * ty
    snt = sec["sxx"] * tx * nx + sec["syy"] * ty * ny + sec["sxy"] * (tx * ny + ty * nx)
    return ((snn, "σn (normal to the section)"), (stt, "σs (along the section)"), (snt, "τns"),
            f"s = ({tx:.2f}, {ty:.2f}), n = ({nx:.2f}, {ny:.2f})")


def section_files(run):
    folder = run.path / "sections"
    if not folder.is_dir():
        return []
    return sorted(f for f in folder.glob("*.csv") if not f.name.endswith("_path.csv"))


def section_pictures(run, out):
    """All sections of a run, final state: one row per section (normal stresses | shear)."""
    files = section_files(run)
    if not files:
        return []
    made = []
    fig, grid = plt.subplots(len(files), 2, figsize=(10.5, 4.6 * len(files) + 0.5), squeeze=False)
    for axes, path in zip(grid, files):
        sname = path.stem
        sec = read_section(path)
        pos, pname, vertical = section_axis(sec)
        (sn, ln), (ss, ls_), (st, lt), note = section_components(sec)
        where = f"({sec['x'][0]:.4g}, {sec['y'][0]:.4g}) → ({sec['x'][-1]:.4g}, {sec['y'][-1]:.4g})"
        plab = f"{pname} ({run.ulen})"
        plot_along(axes[0], pos, sn, vertical, color="tab:blue", marker=".", label=ln)
        plot_along(axes[0], pos, ss, vertical, color="tab:green", ls="--", label=ls_)
        label_axes(axes[0], vertical, plab, f"normal stress ({run.ustress}), tension positive")
        axes[0].legend(fontsize=8)
        axes[0].set_title(f"{sname} {where}: (a) normal stresses", fontsize=9)
        plot_along(axes[1], pos, st, vertical, color="tab:red", marker=".", label=lt)
        label_axes(axes[1], vertical, plab, f"shear stress {lt} ({run.ustress})")
        axes[1].set_title(f"{sname}: (b) shear stress ({note})", fontsize=9)
    suptitle(fig, f"{run.title}\nsections, final state (sections/*.csv)", fontsize=10)
    fig.tight_layout(rect=(0, 0, 1, 1 - 0.45 / fig.get_figheight()))
    name = out / f"{run.name}_sections.png"
    save(fig, name)
    print(f"report: {name}: " + ", ".join(f.stem for f in files))
    made.append(name)
    made += section_history_pictures(run, out, files)
    return made


def state_detached(run):
    """Per archived state: (state name, history row or None, total detached length)."""
    h5 = run.h5
    hist = h5["history"] if "history" in h5 else None
    key = {}
    if hist is not None and hist["load_factor"].shape[0]:
        dl = hist["detached_length"][()].sum(1)
        for j, (ls, it) in enumerate(zip(hist["load_step"][()], hist["iteration"][()])):
            key[(int(ls), int(it))] = (j, float(dl[j]))
    out = []
    for st in run.state_names():
        a = h5["states"][st].attrs
        j, d = key.get((int(a.get("load_step", 0)), int(a.get("iteration", -1))), (None, np.nan))
        out.append((st, j, d))
    return out


def section_states(run, path, sec):
    """The section's stresses along the contact iterations.

    Returns (source, states, check): states in order, each a dict with iteration, load_step,
    d (detached length, all interfaces) and sigma() -> (points, 3) array (xx, yy, xy).
    Source: sgbem's sections/<name>_path.csv when the run wrote it, else pipelines/somigliana.py
    on the archived states' boundary data. `check` compares the two where both exist.
    """
    pts = np.c_[sec["x"], sec["y"]]
    h5 = run.h5
    somig = None
    if h5 is not None and run.state_names():
        if somigliana.has_body_force(h5):
            if not getattr(run, "told_body_force", False):
                print(f"report: {run.path}: body forces present: no Python Somigliana check of the sections "
                      f"(it has no domain integral)")
                run.told_body_force = True
        else:
            bodies = somigliana.archive_bodies(h5)
            somig = lambda st: somigliana.section_stress(h5, bodies, st, pts)  # noqa: E731
    pfile = path.with_name(path.stem + "_path.csv")
    states = []
    if pfile.exists():
        groups = {}
        for r in csv.DictReader(pfile.open()):
            key = (int(r["load_step"]), int(r["iteration"]))
            g = groups.setdefault(key, {"d": float(r["detached_length"]), "rows": []})
            g["rows"].append([float(r[k]) for k in ("x", "y", "sxx", "syy", "sxy")])
        for (ls, it), g in groups.items():
            a = np.array(g["rows"])
            states.append({"iteration": it, "load_step": ls, "d": g["d"], "xy": a[:, :2],
                           "sigma": (lambda a=a: a[:, 2:5])})
        source = f"sgbem's sections/{pfile.name}"
        check = ""
        if somig is not None and states and len(states[0]["xy"]) == len(pts):
            names = {(int(h5["states"][n].attrs.get("load_step", 0)), int(h5["states"][n].attrs["iteration"])): n
                     for n in run.state_names()}
            errs = []
            for st in [states[0], states[len(states) // 2], states[-1]]:
                n = names.get((st["load_step"], st["iteration"]))
                if n is None:
                    continue
                ref = st["sigma"]()
                scale = float(np.nanmax(np.abs(ref))) or 1.0
                errs.append(np.abs(somig(n) - ref).ravel() / scale)
            if errs:
                e = np.concatenate(errs)
                check = (f"independent check by pipelines/somigliana.py at iterations {states[0]['iteration']}, "
                         f"{states[len(states) // 2]['iteration']}, {states[-1]['iteration']}: differences of "
                         f"at most {np.nanmax(e):.1e} (median {np.nanmedian(e):.1e}) of the largest stress, the "
                         f"largest next to the boundary, where sgbem corrects the boundary layer")
        return source, states, check
    if somig is None or (len(run.state_names()) < 2 and "beam" not in PAPER.get(run.name, {})):
        return "", [], ""
    for st, row, d in state_detached(run):
        a = h5["states"][st].attrs
        states.append({"iteration": int(a.get("iteration", 0)), "load_step": int(a.get("load_step", 0)),
                       "d": d, "xy": pts, "sigma": (lambda st=st: somig(st))})
    ref = np.c_[sec["sxx"], sec["syy"], sec["sxy"]]
    scale = float(np.nanmax(np.abs(ref))) or 1.0
    err = np.abs(states[-1]["sigma"]() - ref) / scale
    source = (f"pipelines/somigliana.py from the archived boundary data (this run has no "
              f"sections/{pfile.name})")
    check = (f"at the final state it differs from sgbem's sections/{path.name} by at most "
             f"{np.nanmax(err):.1e} (median {np.nanmedian(err):.1e}) of the largest stress")
    return source, states, check


def section_history_pictures(run, out, files):
    """The normal stress along each section for five states of the contact iterations."""
    made = []
    paper = PAPER.get(run.name, {})
    panels = []
    for path in files:
        sec = read_section(path)
        source, states, check = section_states(run, path, sec)
        if not states:
            continue
        print(f"report: {run.path}: section {path.stem} along the iterations from {source}"
              + (f"; {check}" if check else ""))
        if "beam" in paper:
            made += beam_picture(run, out, path, sec, states, source, check)
        if len(states) > 1:
            panels.append((path, sec, source, check, states))
    if not panels:
        return made
    ncol = min(3, len(panels))
    nrow = (len(panels) + ncol - 1) // ncol
    fig, grid = plt.subplots(nrow, ncol, figsize=(6.6 * ncol, 6.0 * nrow + 0.9), squeeze=False)
    notes = []
    for ax, (path, sec, source, check, states) in zip(grid.ravel(), panels):
        sname = path.stem
        pos, pname, vertical = section_axis(sec)
        (sn, ln), _, _, _ = section_components(sec)
        d = np.array([st["d"] for st in states])
        targets = paper.get("fig6_d") or (list(np.linspace(0.0, np.nanmax(d), 5)) if np.isfinite(d).any() else [])
        picks = []
        for t in targets:
            j = int(np.nanargmin(np.abs(d - t)))
            if j not in picks:
                picks.append(j)
        cmap = plt.cm.plasma
        for n, j in enumerate(picks):
            st = states[j]
            sig = st["sigma"]()
            one = {"sxx": sig[:, 0], "syy": sig[:, 1], "sxy": sig[:, 2], "x": st["xy"][:, 0], "y": st["xy"][:, 1]}
            (vals, _), _, _, _ = section_components(one)
            plot_along(ax, pos, vals, vertical, color=cmap(n / max(len(picks), 1) * 0.9), marker=".", ms=3,
                       label=f"d = {st['d']:.2f} {run.ulen} (iteration {st['iteration']})")
        plot_along(ax, pos, sn, vertical, color="k", ls=":", lw=1.0, label=f"sections/{path.name} (final)")
        label_axes(ax, vertical, f"{pname} ({run.ulen})", f"{ln} ({run.ustress}), tension positive")
        ax.legend(fontsize=7.5, loc="best")
        ax.set_title(f"section {sname}", fontsize=9.5)
        notes.append(f"{sname}: {source}" + (f"; {check}" if check else ""))
        print(f"report: {run.path}: section {sname}: iterations "
              + ", ".join(f"{states[j]['iteration']} (d={states[j]['d']:.2f})" for j in picks))
    for ax in grid.ravel()[len(panels):]:
        ax.axis("off")
    what = ("the paper's Fig. 6: d = " + ", ".join(f"{t:g}" for t in paper["fig6_d"])) if "fig6_d" in paper \
        else "five states from the first to the last"
    if len(set(n.split(": ", 1)[1] for n in notes)) == 1:
        notes = [notes[0].split(": ", 1)[1]]
    suptitle(fig, f"{run.title}\nnormal stress on the sections during the contact iterations ({what}; "
                  f"d = detached length, all interfaces)\nvalues: " + " | ".join(notes), fontsize=8.5)
    fig.tight_layout()
    name = out / f"{run.name}_sections_history.png"
    save(fig, name)
    print(f"report: {name}")
    made.append(name)
    return made


def beam_picture(run, out, path, sec, states, source, check):
    """The paper's Fig. 5: sigma_x and tau_xy at the section against beam theory."""
    b = PAPER[run.name]["beam"]
    q, L, h, w = b["q"], b["L"], b["h"], b["b"]
    sname = path.stem
    x = float(np.mean(sec["x"]))
    if np.ptp(sec["x"]) > 1e-9 * L:
        print(f"report: {run.path}: section {sname} is not vertical: no beam-theory picture")
        return []
    inertia = w * h ** 3 / 12.0
    y = np.linspace(sec["y"].min(), sec["y"].max(), 201)
    ymid = 0.5 * (sec["y"].min() + sec["y"].max())
    yc = y - ymid
    M = q * (6 * L * x - 6 * x ** 2 - L ** 2) / 12.0   # sagging positive
    V = q * (L / 2 - x)                                 # V = dM/dx
    sx_beam = -M * yc / inertia
    S = w * (h ** 2 / 4 - yc ** 2) / 2.0                 # first moment of the part above y
    tau_beam = -V * S / (inertia * w)                    # elasticity sign: tau_xy = -V S / (I b)

    first = states[0]
    sig0 = first["sigma"]()
    y0 = first["xy"][:, 1]
    dfin = states[-1]["d"]
    fig, axes = plt.subplots(1, 2, figsize=(11, 5.8))
    ax = axes[0]
    ax.plot(sx_beam, y, color="0.2", lw=1.2, label="beam theory, continuous beam")
    ax.plot(sig0[:, 0], y0, "o", color="tab:blue", ms=3.5, mfc="none",
            label=f"sgbem, iteration {first['iteration']} (d = {first['d']:.2f} {run.ulen}, joint closed)")
    ax.plot(sec["sxx"], sec["y"], ".-", color="tab:red", ms=4, lw=1.0,
            label=f"sgbem, final (d = {dfin:.2f} {run.ulen})")
    label_axes(ax, True, f"y ({run.ulen})", f"σx ({run.ustress})")
    ax.set_title(f"(a) σx = −M y′/I, M(x) = q(6Lx − 6x² − L²)/12 = {M:.4g} {run.uforce}·{run.ulen}", fontsize=9)
    ax.legend(fontsize=7.5, loc="best")
    ax = axes[1]
    ax.plot(tau_beam, y, color="0.2", lw=1.2, label="beam theory: τxy = −V·S/(I b)")
    ax.plot(sig0[:, 2], y0, "o", color="tab:blue", ms=3.5, mfc="none",
            label=f"sgbem, iteration {first['iteration']} (joint closed)")
    ax.plot(sec["sxy"], sec["y"], ".-", color="tab:red", ms=4, lw=1.0, label="sgbem, final")
    label_axes(ax, True, f"y ({run.ulen})", f"τxy ({run.ustress})")
    ax.set_title(f"(b) V = dM/dx = q(L/2 − x) = {V:.4g} {run.uforce}; max |τ| = 1.5 V/A = {1.5 * abs(V) / (w * h):.4g}",
                 fontsize=9)
    ax.legend(fontsize=7.5, loc="best")
    suptitle(fig,
             f"{run.title}: section {sname} at x = {x:g} {run.ulen} (the paper's Fig. 5)\n"
             f"q = {q:g} {run.uforce}/{run.ulen}, L = {L:g}, I = b h³/12 = {inertia:.5g} {run.ulen}⁴ "
             f"(b = {w:g}, h = {h:g}); y′ = y − {ymid:g} upward from the centroid; M sagging positive, "
             f"σx tension positive, τxy = σxy in the x, y axes (so the beam's V·S/(I b) enters with a minus sign)\n"
             f"iteration {first['iteration']}: {source}" + (f"; {check}" if check else ""),
             fontsize=7.5)
    fig.tight_layout()
    name = out / f"{run.name}_section_{sname}_beam.png"
    save(fig, name)
    k = int(np.argmin(y0))
    print(f"report: {name}: σx at the bottom: beam theory {sx_beam[0]:.4g}, sgbem iteration "
          f"{first['iteration']} {sig0[k, 0]:.4g}")
    return [name]


# --------------------------------------------------------------------------------------
def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("runs", nargs="+", type=pathlib.Path, help="run folders (sgbem run --out)")
    ap.add_argument("--out", type=pathlib.Path, default=pathlib.Path("docs/img"))
    args = ap.parse_args()
    try:
        import vtk
        vtk.vtkLogger.SetStderrVerbosity(vtk.vtkLogger.VERBOSITY_OFF)
    except Exception:
        pass
    args.out.mkdir(parents=True, exist_ok=True)
    made, failed = [], []
    for path in args.runs:
        path = path.resolve() if not path.exists() else path
        if not (path / "summary.json").exists():
            print(f"report: {path}: no summary.json (run `sgbem run SCENE --out {path}` first): skipped")
            continue
        try:
            run = Run(path)
        except Exception as e:
            print(f"report: {path}: cannot read the run ({e}): skipped")
            failed.append(f"{path}")
            continue
        for fn in (shape_picture, detachment_pictures, section_pictures):
            try:
                made += fn(run, args.out)
            except Exception:
                failed.append(f"{path}: {fn.__name__}")
                print(f"report: {path}: {fn.__name__} failed:\n{traceback.format_exc()}", file=sys.stderr)
        run.close()
    print(f"report: {len(made)} pictures in {args.out}")
    if failed:
        print("report: failed: " + "; ".join(failed), file=sys.stderr)
        sys.exit(1)


if __name__ == "__main__":
    main()
