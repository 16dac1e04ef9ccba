"""Open every output of a run folder with independent readers and check that they agree.

Readers: h5py (archive.h5), meshio and pyvista (vtk/*.vtu), xml.etree (vtk/history.pvd),
csv (interfaces/*.csv, sections/*.csv), json (summary.json). Checks:
  archive    root attributes (format, version, units, scene, mesh digest); shapes and index
             ranges of /mesh, /bodies, /interfaces, /states, /solution, /history; operator
             shapes (D00 symmetric); every dataset has description and units;
  summary    title, status, counts and per-interface figures (detached and closed lengths,
             open pairs, resultants, extreme tractions) recomputed from /solution; timings;
  history    detached lengths recomputed from each row's statuses;
  csv        interface tables agree with /solution; section tables have their columns;
  thrust     thrust.csv and summary.json `thrust`: per joint N, T, the point of application
             and its eccentricity recomputed from /solution (docs/thrust.md); the last VTK
             thrust file holds the same points;
  hubs       thrust_hubs.csv: its header and units, one row per body at most, in body order,
             bodies that exist, finite numbers and a resultant, group below or above, and
             joints (more than two) the body's loaded joints in thrust.csv; the last VTK
             thrust file holds the same hubs (its points of joint -1);
  contact    the VTK contact block of every archived state (contact_NNNN.vtu, block
             "contact" of state_NNNN.vtm): a vertex per pair at the archive's pair point,
             interface and pair indices, interface_names in run order, contact_status,
             tangential_status, normal traction and opening, forces (traction x tributary
             length x thickness) equal to the archive's state; for the final state
             contact_status and normal_traction equal to the interface CSVs and each
             interface's normal_force adding up to -N of thrust.csv;
  vtk        history.pvd lists existing files, one boundary file per archived state, times
             increasing; each file read by meshio and pyvista with the point data of README
             "Outputs" and values equal to the archive's.
Usage: check_outputs.py RUN_DIR      (exit 1 with one line per disagreement)
"""
import csv
import json
import pathlib
import sys
import tomllib
import xml.etree.ElementTree as ET

import h5py
import meshio
import numpy as np
import pyvista

BOUNDARY_DATA = {"displacement": 3, "traction": 3, "normal": 3, "contact_status": 1,
                 "normal_traction": 1, "normal_opening": 1, "body": 1}
FIELD_DATA = {"displacement": 3, "stress": 6, "sxx": 1, "syy": 1, "szz": 1, "sxy": 1, "von_mises": 1,
              "principal_stress": 3, "body": 1}
CONTACT_DATA = {"interface": 1, "pair": 1, "contact_status": 1, "tangential_status": 1, "gap": 1,
                "normal_opening": 1, "normal_traction": 1, "tangential_traction": 1, "normal_force": 1,
                "tangential_force": 1, "slip": 1, "displacement": 3}
REL = 1e-9
TITLE = [""]   # the run's title, from summary.json
CODES = {"closed": 1, "open": 0}   # contact_status of the interface CSVs


class Checker:
    def __init__(self, run):
        self.run = run
        self.failures = []
        self.checked = 0

    def ok(self, cond, message):
        self.checked += 1
        if not cond:
            self.failures.append(message)
        return cond

    def close(self, a, b, message, scale=1.0):
        a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
        if a.shape != b.shape:
            return self.ok(False, f"{message}: shapes {a.shape} and {b.shape}")
        tol = REL * max(scale, float(np.max(np.abs(b), initial=0.0)), 1e-300)
        err = float(np.max(np.abs(a - b), initial=0.0))
        return self.ok(err <= tol, f"{message}: differ by {err:.3e} (tolerance {tol:.3e})")


def text(v):
    return v.decode() if isinstance(v, bytes) else str(v)


def names(group):
    return [text(n) for n in group.attrs["order"]]


def segment_lengths(x, elements):
    return np.hypot(*(x[elements[:, 1]] - x[elements[:, 0]]).T) if len(elements) else np.zeros(0)


def check_archive(c, h5, summary):
    a = h5.attrs
    c.ok(text(a.get("format", "")) == "sgbem-archive", "archive: root attribute format is not sgbem-archive")
    for key in ["format_version", "tool_version", "scene", "mesh_sha256", "units"]:
        c.ok(key in a, f"archive: root attribute {key} missing")
    # The date lives with the timings, out of the deterministic part of the archive.
    c.ok("created" not in a, "archive: root attribute created (a date) should be in /timings")
    c.ok("created" in h5["timings"].attrs, "archive: /timings has no created attribute")
    digest = text(a.get("mesh_sha256", ""))
    c.ok(digest == "" or (len(digest) == 64 and all(ch in "0123456789abcdef" for ch in digest)),
         f"archive: mesh_sha256 {digest!r} is not a SHA-256 digest")
    units = json.loads(text(a.get("units", "{}")))
    c.ok({"length", "force"} <= set(units), f"archive: units {units} lacks length or force")
    if "title" in summary:
        c.ok(text(a.get("title", "")) == summary["title"], "archive title differs from summary.json")
    if "status" in summary:
        c.ok(text(a.get("status", "")) == summary["status"],
             f"archive status {text(a.get('status', ''))!r} differs from summary.json {summary['status']!r}")

    missing = []
    h5.visititems(lambda name, obj: missing.append(name) if isinstance(obj, h5py.Dataset)
                  and not {"description", "units"} <= set(obj.attrs) else None)
    c.ok(not missing, f"archive: datasets without description/units: {missing[:5]}")

    mesh = h5["mesh"]
    nn = mesh["nodes"].shape[0]
    c.ok(mesh["nodes"].shape == (nn, 2), "/mesh/nodes is not N x 2")
    nl = mesh["lines"].shape[0]
    c.ok(mesh["lines"].shape == (nl, 2), "/mesh/lines is not L x 2")
    c.ok(mesh["line_group"].shape == (nl,), "/mesh/line_group does not match /mesh/lines")
    c.ok(nl == 0 or mesh["lines"][()].max() < nn, "/mesh/lines refers beyond /mesh/nodes")
    c.ok(nl == 0 or mesh["line_group"][()].max() < mesh["group_names"].shape[0],
         "/mesh/line_group refers beyond /mesh/group_names")

    bodies = [h5["bodies"][n] for n in names(h5["bodies"])]
    counts = summary.get("counts", {})
    if "bodies" in counts:
        c.ok(len(bodies) == counts["bodies"], f"{len(bodies)} bodies in the archive, {counts['bodies']} in summary.json")
    ne = sum(b["elements"].shape[0] for b in bodies)
    if "boundary_elements" in counts:
        c.ok(ne == counts["boundary_elements"], f"{ne} boundary elements in the archive, {counts['boundary_elements']} in summary.json")
    dofs = 0
    for b in bodies:
        n, m = b["nodes"].shape[0], b["elements"].shape[0]
        c.ok(b["nodes"].shape == (n, 2), f"{b.name}/nodes is not n x 2")
        c.ok(b["elements"].shape == (m, 2), f"{b.name}/elements is not m x 2")
        c.ok(m == 0 or b["elements"][()].max() < n, f"{b.name}/elements refers beyond its nodes")
        c.ok(n == 0 or b["mesh_nodes"][()].max() < nn, f"{b.name}/mesh_nodes refers beyond /mesh/nodes")
        c.ok(np.array_equal(b["nodes"][()], mesh["nodes"][()][b["mesh_nodes"][()]]),
             f"{b.name}/nodes differ from the mesh nodes they name")
        if "D00" in b:
            nu = b["unknowns"].shape[0]
            nx = int(b.attrs["n_x"])
            dofs += nu
            for key, shape in [("A", (nx, nx)), ("A0", (nx, nu - nx)), ("A00", (nu - nx, nu - nx)),
                               ("D00", (nu - nx, nu - nx)), ("Z0", (nu - nx,)), ("load", (nu,))]:
                c.ok(b[key].shape == shape, f"{b.name}/{key} has shape {b[key].shape}, expected {shape}")
            d = b["D00"][()]
            if d.size:
                c.ok(np.max(np.abs(d - d.T)) <= 1e-10 * np.max(np.abs(d)), f"{b.name}/D00 is not symmetric")
    if dofs and "dofs" in counts:
        c.ok(dofs == counts["dofs"], f"{dofs} unknowns in the archived operators, {counts['dofs']} dofs in summary.json")

    ifaces = [h5["interfaces"][n] for n in names(h5["interfaces"])]
    np_total = sum(i["x"].shape[0] for i in ifaces)
    if "interface_pairs" in counts:
        c.ok(np_total == counts["interface_pairs"], f"{np_total} interface pairs in the archive, {counts['interface_pairs']} in summary.json")
    for i in ifaces:
        p = i["x"].shape[0]
        for key in ["normal", "tangent"]:
            c.ok(i[key].shape == (p, 2), f"{i.name}/{key} is not pairs x 2")
        for key in ["gap", "cohesion", "s", "node_a", "node_b"]:
            c.ok(i[key].shape == (p,), f"{i.name}/{key} does not have one value per pair")
    return bodies, ifaces


def check_solution(c, h5, summary, bodies, ifaces):
    states = h5["states"]
    count = int(states.attrs["count"])
    groups = [k for k, v in states.items() if isinstance(v, h5py.Group)]
    c.ok(len(groups) == count, f"/states holds {len(groups)} groups, its count says {count}")
    if count == 0:
        return count
    sol = h5["solution"]
    last = states[f"{count - 1:04d}"]
    c.ok(sol.attrs["iteration"] == last.attrs["iteration"], "/solution is not the last state")
    # The compact states: offsets match the bodies and interfaces; the last state holds the
    # values of /solution.
    order = [text(n) for n in h5["bodies"].attrs["order"]]
    no = np.concatenate([[0], np.cumsum([h5["bodies"][n]["nodes"].shape[0] for n in order])])
    c.ok(np.array_equal(states["node_offset"][()], no), "/states/node_offset does not match /bodies")
    u = np.vstack([sol["bodies"][n]["u"][()] for n in order])
    c.close(last["u"][()], u, "/states: the last state's u vs /solution", float(np.abs(u).max()) or 1.0)
    iorder = [text(n) for n in h5["interfaces"].attrs["order"]]
    if iorder:
        st = np.concatenate([sol["interfaces"][n]["status"][()] for n in iorder])
        c.ok(np.array_equal(last["status"][()], st), "/states: the last state's status vs /solution")
    thickness = float(h5.attrs.get("thickness", 1.0))
    for b in bodies:
        name = text(b.attrs["name"])
        g = sol["bodies"][b.name.split("/")[-1]]
        c.ok(g["u"].shape == b["nodes"].shape, f"/solution u of {name} does not match its nodes")
        c.ok(g["t"].shape == (b["elements"].shape[0], 2, 2), f"/solution t of {name} is not elements x 2 x 2")
    figures = summary.get("interfaces", {})
    for i in ifaces:
        name = text(i.attrs["name"])
        r = sol["interfaces"][i.name.split("/")[-1]]
        status, traction = r["status"][()], r["traction"][()]
        x, elements = i["x"][()], i["elements"][()]
        c.ok(status.shape == (x.shape[0],), f"/solution status of {name} does not have one value per pair")
        if name not in figures:
            c.ok(False, f"summary.json has no figures for interface {name}")
            continue
        s = figures[name]
        lengths = segment_lengths(x, elements)
        open_ = status == 0
        both_open = open_[elements[:, 0]] & open_[elements[:, 1]] if len(elements) else np.zeros(0, bool)
        both_closed = ~open_[elements[:, 0]] & ~open_[elements[:, 1]] if len(elements) else np.zeros(0, bool)
        scale = float(lengths.sum()) or 1.0
        expect = {
            "detached_length": lengths[both_open].sum(),
            "closed_length": lengths[both_closed].sum(),
            "open_pairs": int(open_.sum()),
            "pairs": x.shape[0],
        }
        if len(elements):
            tn = traction[:, 1]
            if "pairing" in i:
                # Sides meshed on their own: the pairs' own tributary lengths (the parts of
                # body A that face body B).
                expect["normal_resultant"] = thickness * float(np.sum(i["pairing"]["weight"][()] * tn))
            else:
                expect["normal_resultant"] = thickness * float(np.sum(0.5 * lengths * (tn[elements[:, 0]] + tn[elements[:, 1]])))
            expect["max_normal_traction"] = float(tn.max())
            expect["min_normal_traction"] = float(tn.min())
        tscale = float(np.max(np.abs(traction), initial=0.0)) or 1.0
        for key, want in expect.items():
            if key not in s:
                continue
            sc = scale if "length" in key else tscale * scale * thickness if key == "normal_resultant" else tscale
            c.close(s[key], want, f"interface {name}: summary {key} vs the archive's final state", sc)
    if "field_nodes" in summary.get("counts", {}) and "interior" in sol:
        k = sum(g["mesh_nodes"].shape[0] for g in sol["interior"].values())
        c.ok(k == summary["counts"]["field_nodes"], f"{k} interior points archived, {summary['counts']['field_nodes']} field nodes in summary.json")
    return count


def check_history(c, h5, ifaces):
    h = h5["history"]
    nr = h["load_factor"].shape[0]
    for key in ["load_step", "iteration", "solver"]:
        c.ok(h[key].shape == (nr,), f"/history/{key} does not have one value per row")
    dl = h["detached_length"][()]
    c.ok(dl.shape == (nr, len(ifaces)), f"/history/detached_length has shape {dl.shape}, expected {(nr, len(ifaces))}")
    for k, i in enumerate(ifaces):
        name = text(i.attrs["name"])
        g = h["interfaces"][i.name.split("/")[-1]]
        st = g["status"][()]
        p = i["x"].shape[0]
        c.ok(st.shape == (nr, p), f"/history status of {name} is not rows x pairs")
        if st.shape != (nr, p) or dl.shape != (nr, len(ifaces)):
            continue
        # The last history row is the final solution.
        if nr > 0 and "solution" in h5:
            fin = h5["solution"]["interfaces"][i.name.split("/")[-1]]
            c.ok(np.array_equal(st[-1], fin["status"][()]),
                 f"/history: the last row's status of {name} differs from /solution")
            c.close(g["normal_traction"][()][-1], fin["traction"][()][:, 1],
                    f"/history: the last row's normal traction of {name} vs /solution")
        lengths = segment_lengths(i["x"][()], i["elements"][()])
        e = i["elements"][()]
        for r in range(nr):
            if len(e) == 0:
                break
            both = (st[r, e[:, 0]] == 0) & (st[r, e[:, 1]] == 0)
            c.close(dl[r, k], lengths[both].sum(), f"/history row {r}: detached length of {name} vs its statuses",
                    float(lengths.sum()) or 1.0)


def check_timings(c, h5, run):
    c.ok("timings" not in json.loads((run / "summary.json").read_text()),
         "summary.json holds timings (they belong in timings.json)")
    path = run / "timings.json"
    if not c.ok(path.exists(), f"{path} is missing"):
        return
    t = json.loads(path.read_text()).get("stages", {})
    for stage in names(h5["timings"]):
        if not c.ok(stage in t, f"timing stage {stage} is in the archive but not in timings.json"):
            continue
        if stage not in ("write", "total"):
            c.close(h5["timings"][stage][()], t[stage], f"timing of stage {stage}: archive vs timings.json", 1e-6)


def tributary(i, x, elements):
    """Each pair's tributary length: the pairing's weights, else half of each adjacent element."""
    if "pairing" in i:
        return i["pairing"]["weight"][()]
    w = np.zeros(x.shape[0])
    lengths = segment_lengths(x, elements)
    for (j, k), length in zip(elements, lengths):
        w[j] += 0.5 * length
        w[k] += 0.5 * length
    return w


def check_thrust(c, run, h5, summary, ifaces):
    path = run / "thrust.csv"
    if not c.ok(path.exists() == bool(ifaces), f"{path}: written {path.exists()}, interfaces {len(ifaces)}"):
        return
    if not ifaces:
        return
    rows = list(csv.reader(path.open()))
    header, rows = rows[0], rows[1:]
    c.ok([h.split(" [")[0] for h in header] == ["joint", "body_a", "body_b", "N", "T", "x", "y", "s", "e",
                                               "e_over_half_length", "inside", "in_closed_part"],
         f"{path}: header {header}")
    c.ok(len(rows) == len(ifaces), f"{path}: {len(rows)} rows for {len(ifaces)} interfaces")
    thickness = float(h5.attrs.get("thickness", 1.0))
    sol = h5["solution"]["interfaces"]
    points = []
    for i, row in zip(ifaces, rows):
        name = text(i.attrs["name"])
        c.ok(row[0] == name, f"{path}: row {row[0]}, want {name} (run order)")
        r = sol[i.name.split("/")[-1]]
        traction, x, s = r["traction"][()], i["x"][()], i["s"][()]
        w = tributary(i, x, i["elements"][()])
        f = traction[:, 1] * w
        n, tt = -thickness * f.sum(), thickness * float(np.sum(traction[:, 0] * w))
        scale = thickness * float(np.sum(np.abs(f))) or 1.0
        c.close(float(row[3]), n, f"{path}: {name} N vs the archive", scale)
        c.close(float(row[4]), tt, f"{path}: {name} T vs the archive",
                thickness * float(np.sum(np.abs(traction[:, 0] * w))) or 1.0)
        figures = summary.get("thrust", {}).get(name, {})
        c.ok(figures.get("normal_force") == float(row[3]), f"{path}: {name} N differs from summary.json")
        if not np.any(f):
            c.ok(all(v == "" for v in row[5:]), f"{path}: {name} is fully open but has a point")
            continue
        span = s[w > 0]
        xc, sc = (x * f[:, None]).sum(axis=0) / f.sum(), float(np.sum(s * f) / f.sum())
        length = float(span.max() - span.min())
        e = sc - 0.5 * (span.max() + span.min())
        c.close([float(v) for v in row[5:9]], [xc[0], xc[1], sc, e], f"{path}: {name} point vs the archive",
                float(np.abs(x).max()) or 1.0)
        c.ok(row[10] == ("true" if abs(e) <= 0.5 * length * (1 + 1e-9) else "false"),
             f"{path}: {name} inside {row[10]} with e {e} and L {length}")
        c.ok(figures.get("x") == float(row[5]), f"{path}: {name} x differs from summary.json")
        points.append(xc)
    last = sorted((run / "vtk").glob("thrust_*.vtu"))
    if last:
        m = meshio.read(last[-1])
        # The joints' points (a body's hub, joint -1, is no joint's: docs/thrust.md).
        joints = m.points[np.asarray(m.point_data["joint"]).ravel() >= 0]
        c.close(joints[:, :2], np.array(points).reshape(-1, 2), f"{last[-1]}: points vs thrust.csv",
                float(np.abs(m.points).max(initial=1.0)))


def csv_units(h5):
    """The scene's force and length units as the CSV headers write them."""
    units = json.loads(text(h5.attrs.get("units", "{}")))
    return units.get("force") or "force", units.get("length") or "length"


def check_hubs(c, run, h5, ifaces):
    """thrust_hubs.csv (docs/thrust.md "Bodies with more joints"), final state."""
    path = run / "thrust_hubs.csv"
    if not c.ok(path.exists() == bool(ifaces), f"{path}: written {path.exists()}, interfaces {len(ifaces)}"):
        return
    if not ifaces:
        return
    force, length = csv_units(h5)
    rows = list(csv.reader(path.open()))
    header, rows = rows[0], rows[1:]
    c.ok(header == ["body", f"x [{length}]", f"y [{length}]", f"R_x [{force}]", f"R_y [{force}]", "group", "joints"],
         f"{path}: header {header}")
    bodies = [text(h5["bodies"][n].attrs["name"]) for n in names(h5["bodies"])]
    # The loaded joints (those with a point of application) of each body, from thrust.csv.
    loaded = {}
    tpath = run / "thrust.csv"
    if tpath.exists():
        for r in list(csv.reader(tpath.open()))[1:]:
            if r[5] != "":
                for b in (r[1], r[2]):
                    loaded[b] = loaded.get(b, 0) + 1
    c.ok(len({r[0] for r in rows}) == len(rows), f"{path}: a body has more than one row")
    index = []
    for r in rows:
        if not c.ok(len(r) == 7, f"{path}: row {r} does not have 7 fields"):
            continue
        body = r[0]
        if c.ok(body in bodies, f"{path}: body {body!r} is not one of the run's"):
            index.append(bodies.index(body))
        try:
            values = np.array([float(v) for v in r[1:5]])
        except ValueError:
            c.ok(False, f"{path}: {body}: not numbers: {r[1:5]}")
            continue
        c.ok(np.all(np.isfinite(values)), f"{path}: {body}: numbers not finite: {r[1:5]}")
        c.ok(np.hypot(values[2], values[3]) > 0, f"{path}: {body}: no resultant")
        c.ok(r[5] in ("below", "above"), f"{path}: {body}: group {r[5]!r}, not below or above")
        c.ok(r[6].isdigit() and int(r[6]) > 2, f"{path}: {body}: joints {r[6]!r}, not more than two")
        c.ok(r[6].isdigit() and int(r[6]) == loaded.get(body, 0),
             f"{path}: {body}: joints {r[6]}, thrust.csv gives it {loaded.get(body, 0)} loaded joints")
    c.ok(index == sorted(index), f"{path}: rows not in body order")
    last = sorted((run / "vtk").glob("thrust_*.vtu"))
    if last and all(len(r) == 7 for r in rows):
        m = meshio.read(last[-1])
        at = m.points[np.asarray(m.point_data["joint"]).ravel() == -1][:, :2]
        want = np.array([[float(r[1]), float(r[2])] for r in rows]).reshape(-1, 2)
        c.close(at, want, f"{last[-1]}: hubs (joint -1) vs {path.name}", float(np.abs(m.points).max(initial=1.0)))


def check_contact(c, run, h5, ifaces, count):
    """The VTK block "contact" of every archived state against the archive; the final
    state's against the interface CSVs and thrust.csv."""
    vtk = run / "vtk"
    if not (vtk / "history.pvd").exists():
        return
    files = sorted(vtk.glob("contact_*.vtu"))
    if not ifaces:
        c.ok(not files, f"{vtk}: contact files without interfaces")
        return
    c.ok(len(files) == count, f"{vtk}: {len(files)} contact files for {count} archived states")
    run_names = [text(i.attrs["name"]) for i in ifaces]
    sizes = [i["x"].shape[0] for i in ifaces]
    x = np.vstack([i["x"][()] for i in ifaces])
    thickness = float(h5.attrs.get("thickness", 1.0))
    weight = np.concatenate([tributary(i, i["x"][()], i["elements"][()]) for i in ifaces]) * thickness
    which = np.repeat(np.arange(len(ifaces)), sizes)
    pair = np.concatenate([np.arange(n) for n in sizes])
    states = h5["states"]
    for k in range(count):
        path = vtk / f"contact_{k:04d}.vtu"
        vtm = vtk / f"state_{k:04d}.vtm"
        if not c.ok(path.exists(), f"{path} is missing"):
            continue
        if c.ok(vtm.exists(), f"{vtm} is missing"):
            blocks = {e.get("name"): e.get("file") for e in ET.parse(vtm).getroot().iter("DataSet")}
            c.ok(blocks.get("contact") == path.name, f"{vtm}: block contact is {blocks.get('contact')}")
        m = read_vtu(c, path, CONTACT_DATA)
        st = states[f"{k:04d}"]
        d = m.point_data
        if not c.ok(len(m.points) == len(x), f"{path}: {len(m.points)} points for {len(x)} pairs"):
            continue
        if not c.ok(set(CONTACT_DATA) <= set(d), f"{path}: point data {sorted(d)}"):
            continue
        vertices = sum(len(cb.data) for cb in m.cells if cb.type == "vertex")
        c.ok(vertices == len(x), f"{path}: {vertices} vertices for {len(x)} pairs")
        got = bytes(np.asarray(m.field_data.get("interface_names", []), dtype=np.uint8)).decode()
        c.ok(got.split("\n") == run_names, f"{path}: interface_names differ from the run order")
        c.ok(float(np.ravel(m.field_data["iteration"])[0]) == float(st.attrs["iteration"]),
             f"{path}: iteration differs from the archive's state {k}")
        c.ok(np.array_equal(d["interface"], which), f"{path}: interface indices")
        c.ok(np.array_equal(d["pair"], pair), f"{path}: pair indices")
        c.close(m.points[:, :2], x, f"{path}: points vs the archive's pair points")
        status = st["status"][()]
        c.ok(np.array_equal(d["contact_status"], status), f"{path}: contact_status vs the archive's state {k}")
        ts = st["tangential_status"][()].astype(int) if "tangential_status" in st else np.full(len(x), -1)
        ts = np.where((status == 0) & (ts != -1), 0, ts)      # an open friction pair: 0
        c.ok(np.array_equal(d["tangential_status"], ts), f"{path}: tangential_status vs the archive's state {k}")
        traction = st["traction"][()]
        c.close(d["normal_traction"], traction[:, 1], f"{path}: normal_traction vs the archive's state {k}")
        c.close(d["tangential_traction"], traction[:, 0], f"{path}: tangential_traction vs the archive's state {k}")
        c.close(d["normal_opening"], st["normal_opening"][()], f"{path}: normal_opening vs the archive's state {k}")
        fscale = float(np.max(np.abs(traction), initial=0.0) * np.max(weight, initial=0.0)) or 1.0
        c.close(d["normal_force"], traction[:, 1] * weight, f"{path}: normal_force vs traction x length", fscale)
        c.close(d["tangential_force"], traction[:, 0] * weight, f"{path}: tangential_force vs traction x length",
                fscale)
        if k != count - 1:
            continue
        # The final state: the interface tables and the thrust line.
        thrust = {}
        tpath = run / "thrust.csv"
        if tpath.exists():
            thrust = {r[0]: r[3] for r in list(csv.reader(tpath.open()))[1:]}
        for i, name in enumerate(run_names):
            at = which == i
            tpath_i = run / "interfaces" / f"{name}.csv"
            if tpath_i.exists():
                rows = list(csv.DictReader(tpath_i.open()))
                if c.ok(len(rows) == at.sum(), f"{path}: {at.sum()} points of {name}, its table {len(rows)} rows"):
                    c.ok([CODES[r["status"]] for r in rows] == list(d["contact_status"][at]),
                         f"{path}: contact_status of {name} vs {tpath_i.name}")
                    c.close(d["normal_traction"][at], [float(r["normal_traction"]) for r in rows],
                            f"{path}: normal_traction of {name} vs {tpath_i.name}")
            if name in thrust and thrust[name] != "":
                f = d["normal_force"][at]
                c.close(f.sum(), -float(thrust[name]), f"{path}: normal_force of {name} vs -N of thrust.csv",
                        float(np.abs(f).sum()) or 1.0)


def check_csv(c, run, h5, ifaces):
    for i in ifaces:
        name = text(i.attrs["name"])
        path = run / "interfaces" / f"{name}.csv"
        if not c.ok(path.exists(), f"{path} is missing"):
            continue
        rows = list(csv.DictReader(path.open()))
        r = h5["solution"]["interfaces"][i.name.split("/")[-1]]
        if not c.ok(len(rows) == i["x"].shape[0], f"{path}: {len(rows)} rows for {i['x'].shape[0]} pairs"):
            continue
        x = np.array([[float(row["x"]), float(row["y"])] for row in rows])
        c.close(x, i["x"][()], f"{path}: x, y vs the archive's pair coordinates")
        status = np.array([1 if row["status"] == "closed" else 0 for row in rows])
        c.ok(np.array_equal(status, r["status"][()]), f"{path}: status differs from the archive's")
        tn = np.array([float(row["normal_traction"]) for row in rows])
        c.close(tn, r["traction"][()][:, 1], f"{path}: normal_traction vs the archive's")
        op = np.array([float(row["normal_opening"]) for row in rows])
        c.close(op, r["normal_opening"][()], f"{path}: normal_opening vs the archive's")
        if "pairing" in i:
            # Sides meshed on their own: the row's body and the element of the other it faces.
            side = text(h5["bodies"][list(names(h5["bodies"]))[int(i.attrs["body_a_index"])]].attrs["name"])
            c.ok(all(row["side"] == side for row in rows), f"{path}: side is not body A ({side})")
            seg = i["pairing"]["segment"][()]
            c.ok(all((row["segment"] == "") == (sg < 0) for row, sg in zip(rows, seg)),
                 f"{path}: segment is empty exactly where no element of body B faces the pair")
    for path in sorted((run / "sections").glob("*.csv")):
        with path.open() as f:
            head = f.readline().strip()
        if path.name.endswith("_path.csv"):
            # The section at every recorded iteration: one block of points per state.
            c.ok(head == "iteration,load_step,load_factor,detached_length,x,y,ux,uy,sxx,syy,sxy",
                 f"{path}: header {head!r}")
            with path.open() as f:
                its = {int(row["iteration"]) for row in csv.DictReader(f)}
            c.ok(len(its) == len(h5["history"]["iteration"][()]) if "history" in h5 else True,
                 f"{path}: {len(its)} iterations, the archive's history has another count")
        else:
            c.ok(head == "x,y,ux,uy,sxx,syy,sxy", f"{path}: header {head!r}")


def selected_arrays(h5):
    """`output.vtk_fields` of the run's scene with its `--set` overrides: the point arrays the
    VTK files hold (None: every one)."""
    fields = tomllib.loads(text(h5.attrs["scene"])).get("output", {}).get("vtk_fields")
    for o in json.loads(text(h5.attrs.get("overrides", "[]"))):
        key, _, value = o.partition("=")
        if key.strip() == "output.vtk_fields":
            fields = tomllib.loads(f"v = {value}")["v"]
    return fields


def read_vtu(c, path, expect_names, selected=None):
    m = meshio.read(path)
    if selected is not None:
        expect_names = {k: n for k, n in expect_names.items() if k in selected}
        c.ok(set(m.point_data) <= set(selected),
             f"{path}: point data {sorted(m.point_data)}, output.vtk_fields selects {sorted(selected)}")
    p = pyvista.read(path)
    c.ok(p.n_points == len(m.points), f"{path}: pyvista reads {p.n_points} points, meshio {len(m.points)}")
    for key, ncomp in expect_names.items():
        if not c.ok(key in m.point_data, f"{path}: point data {key} missing"):
            continue
        d = m.point_data[key]
        got = 1 if d.ndim == 1 else d.shape[1]
        c.ok(got == ncomp, f"{path}: {key} has {got} components, expected {ncomp}")
        c.ok(key in p.point_data, f"{path}: pyvista does not see {key}")
    return m


def check_vtk(c, run, h5, bodies, count):
    vtk = run / "vtk"
    pvd = vtk / "history.pvd"
    selected = selected_arrays(h5)
    if not pvd.exists():
        print(f"check_outputs: {vtk} has no history.pvd (output.vtk = false?): VTK checks skipped")
        return
    entries = ET.parse(pvd).getroot().find("Collection").findall("DataSet")
    times = {}
    for e in entries:
        f = vtk / e.get("file")
        c.ok(f.exists(), f"{pvd} lists {f.name}, which does not exist")
        times.setdefault(e.get("file").split("_")[0], []).append(float(e.get("timestep")))
    bt = times.get("boundary", [])
    c.ok(len(bt) == count, f"{pvd}: {len(bt)} boundary files for {count} archived states")
    c.ok(all(a < b for a, b in zip(bt, bt[1:])), f"{pvd}: boundary times do not increase: {bt}")
    # Times: the states of load step s (from 0) with n states at s + j/n, j = 1..n.
    steps = [int(h5["states"][f"{k:04d}"].attrs["load_step"]) for k in range(count)]
    expect = []
    for k, s in enumerate(steps):
        n = steps.count(s)
        expect.append(s + (k - steps.index(s) + 1) / n)
    c.close(bt, expect, f"{pvd}: times vs load step + iteration within the step / iterations")
    ft = times.get("field", [])
    if ft:
        # ParaView reads a part only when it is listed at every time.
        c.ok(ft == bt, f"{pvd}: the field part is not listed at every time")
        check_pvd_pyvista(c, pvd, bt, selected)
    states = h5["states"]
    for k in range(count):
        st = states[f"{k:04d}"]
        # The interior field of the final state is in /solution.
        interior = h5["solution"].get("interior") if k == count - 1 else None
        path = vtk / f"boundary_{k:04d}.vtu"
        if not c.ok(path.exists(), f"{path} is missing"):
            continue
        m = read_vtu(c, path, BOUNDARY_DATA, selected)
        n = sum(b["nodes"].shape[0] for b in bodies)
        ne = sum(b["elements"].shape[0] for b in bodies)
        c.ok(len(m.points) == n, f"{path}: {len(m.points)} points for {n} body nodes")
        lines = sum(len(cb.data) for cb in m.cells if cb.type == "line")
        c.ok(lines == ne, f"{path}: {lines} lines for {ne} boundary elements")
        if len(m.points) == n and {"displacement", "contact_status"} <= set(m.point_data):
            u = st["u"][()]
            xy = np.vstack([b["nodes"][()] for b in bodies])
            c.close(m.points[:, :2], xy, f"{path}: points vs the archive's body nodes")
            c.close(m.point_data["displacement"][:, :2], u, f"{path}: displacement vs the archive's state {k}")
            c.ok(np.all(m.point_data["displacement"][:, 2] == 0), f"{path}: displacement z is not 0")
            cs = m.point_data["contact_status"]
            # Interface nodes: A's and B's of each pair, or B's own where the sides were
            # meshed on their own.
            sides = sum(i["x"].shape[0] + (i["pairing"]["b_nodes"].shape[0] if "pairing" in i
                                           else i["x"].shape[0])
                        for i in h5["interfaces"].values())
            c.ok(set(np.unique(cs)) <= {-1, 0, 1}, f"{path}: contact_status outside -1, 0, 1")
            c.ok(int(np.sum(cs != -1)) <= sides, f"{path}: more interface nodes than the interfaces have")
        fpath = vtk / f"field_{k:04d}.vtu"
        if interior is not None:
            if not c.ok(fpath.exists(), f"{fpath} is missing though state {k} has interior values"):
                continue
            m = read_vtu(c, fpath, FIELD_DATA, selected)
            tri = sum(len(cb.data) for cb in m.cells if cb.type == "triangle")
            nt = sum(b["triangles"].shape[0] for b in bodies)
            c.ok(tri == nt, f"{fpath}: {tri} triangles for {nt} body triangles")
            u = np.vstack([g["u"][()] for g in (interior[b.name.split("/")[-1]] for b in bodies)])
            if (c.ok(len(m.points) == len(u), f"{fpath}: {len(m.points)} points for {len(u)} interior values")
                    and "displacement" in m.point_data):
                c.close(m.point_data["displacement"][:, :2], u, f"{fpath}: displacement vs the archive's")
        else:
            c.ok(not fpath.exists(), f"{fpath} exists though state {k} has no interior values")


def check_pvd_pyvista(c, pvd, times, selected=None):
    """The series as pyvista reads it: at every time a boundary and a field block, the field
    with the 6-component stress tensor, the scalars sxx, syy, sxy and the title as field data
    (the stress where `output.vtk_fields` selects it)."""
    reader = pyvista.get_reader(str(pvd))
    c.close(reader.time_values, times, f"{pvd}: pyvista's times")
    for t in reader.time_values:
        reader.set_active_time_value(t)
        data = reader.read()
        blocks = [b for b in data if b is not None]
        fields = [b for b in blocks if "stress" in b.point_data]
        if selected is not None and not {"stress", "sxx", "syy", "szz", "sxy"} <= set(selected):
            c.ok(len(blocks) == 2, f"{pvd} at time {t}: pyvista reads {len(blocks)} blocks")
            fields = []
        elif not c.ok(len(blocks) == 2 and len(fields) == 1, f"{pvd} at time {t}: pyvista reads "
                    f"{len(blocks)} blocks, {len(fields)} with stress; want a boundary and a field"):
            continue
        s = fields[0].point_data["stress"] if fields else None
        f = fields[0] if fields else None
        if s is not None and c.ok(s.shape == (f.n_points, 6), f"{pvd} at time {t}: stress shape {s.shape}"):
            for col, name in [(0, "sxx"), (1, "syy"), (2, "szz"), (3, "sxy")]:
                c.ok(name in f.point_data and np.array_equal(f.point_data[name], s[:, col]),
                     f"{pvd} at time {t}: {name} differs from stress column {col}")
            c.ok(np.all(s[:, 4:] == 0), f"{pvd} at time {t}: stress yz, xz are not 0")
        for b in blocks:
            # Text field data: UTF-8 bytes in UInt8 arrays.
            title = bytes(np.asarray(b.field_data.get("title", []), dtype=np.uint8)).decode()
            c.ok(title == TITLE[0], f"{pvd} at time {t}: title field data {title!r}, summary.json {TITLE[0]!r}")
            c.ok("load_factor" in b.field_data, f"{pvd} at time {t}: no load_factor field data")


def main():
    if len(sys.argv) != 2:
        sys.exit("usage: check_outputs.py RUN_DIR")
    run = pathlib.Path(sys.argv[1])
    c = Checker(run)
    for f in ["summary.json", "archive.h5"]:
        if not (run / f).exists():
            sys.exit(f"check_outputs: {run / f} is missing: run `sgbem run SCENE --out {run}` first")
    summary = json.loads((run / "summary.json").read_text())
    TITLE[0] = summary.get("title", "")
    with h5py.File(run / "archive.h5", "r") as h5:
        bodies, ifaces = check_archive(c, h5, summary)
        count = check_solution(c, h5, summary, bodies, ifaces)
        check_history(c, h5, ifaces)
        check_timings(c, h5, run)
        if count:
            check_csv(c, run, h5, ifaces)
            check_thrust(c, run, h5, summary, ifaces)
            check_hubs(c, run, h5, ifaces)
            check_contact(c, run, h5, ifaces, count)
        check_vtk(c, run, h5, bodies, count)
    if c.failures:
        for f in c.failures:
            print(f"check_outputs: {run}: {f}", file=sys.stderr)
        sys.exit(1)
    print(f"check_outputs: {run}: {c.checked} checks passed")


if __name__ == "__main__":
    main()
