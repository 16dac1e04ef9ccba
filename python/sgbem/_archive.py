"""`sgbem.open`: a run folder or its `archive.h5` as Python objects (h5py, pandas, pyvista).

The archive layout is documented in `src/output/archive/mod.rs`. What this module relies on:
`/bodies`, `/interfaces` and `/history/interfaces` carry an `order` attribute with their
children's group names in run order, each child a `name` attribute with its real name;
`/states/NNNN` hold every archived state with the bodies' nodes and elements and the
interfaces' pairs concatenated, sliced by `/states/node_offset`, `element_offset` and
`pair_offset`; `/solution/interior/<body>` holds the interior field of the final state.
The thrust block of `to_pyvista` and the hubs of `Run.hubs` (thrust_hubs.csv) are
computed from the states' tractions and the interfaces' `x`, `s`, `normal` and tributary
lengths, with the bodies' `body_force` (a state's own where it has one) for "down"
(`_thrust.py`), so that an archive copied alone has them.
"""

import json
import pathlib

import h5py
import numpy as np
import pandas as pd

FORMAT = "sgbem-archive"

# Codes of the archive's status datasets.
_STATUS = {1: "closed", 0: "open"}
_TANGENTIAL = {1: "stick", 2: "slip", -1: "none"}


def _text(value):
    """A string attribute or element as `str` (h5py gives bytes or numpy bytes for some)."""
    if isinstance(value, (bytes, np.bytes_)):
        return value.decode("utf-8")
    return str(value)


def _texts(values):
    return [_text(v) for v in np.asarray(values).ravel()]


def _floats(values):
    """Float data with `-0.0` made `0.0` (adding 0.0 does exactly that)."""
    return np.asarray(values, dtype=float) + 0.0


def _tributary(it, x):
    """Each pair's tributary length, as sgbem weighs the pairs: where the sides were meshed
    on their own the pairing's weights, else half of each of the interface's elements that
    joins the pair to another (the integrals of the P1 hats), added element by element."""
    if "pairing" in it:
        return _floats(it["pairing"]["weight"])
    e = np.asarray(it["elements"], dtype=np.int64).reshape(-1, 2)
    w = np.zeros(len(x))
    if len(e):
        d = x[e[:, 1]] - x[e[:, 0]]
        half = 0.5 * np.hypot(d[:, 0], d[:, 1])
        # np.add.at adds in index order: the element's first pair, then its second.
        np.add.at(w, e.ravel(), np.repeat(half, 2))
    return w


def open(path):  # noqa: A001 - the package's documented name, `sgbem.open`
    """Opens a run folder (holding archive.h5) or an archive file; see `Run`."""
    return Run(path)


class Run:
    """The results of one `sgbem run`, read from its archive on demand.

    Attributes read once: `folder`, `archive`, `title`, `status`, `units` (dict: length,
    force, stress), `bodies` and `interfaces` (real names, in run order), `state_count`.
    """

    def __init__(self, path):
        p = pathlib.Path(path)
        if p.is_dir():
            self.folder, self.archive = p, p / "archive.h5"
        else:
            self.folder, self.archive = p.parent, p
        if not self.archive.is_file():
            raise FileNotFoundError(
                f"{self.archive}: no archive: give a run folder written by `sgbem run` "
                f"(it holds archive.h5) or the path of an archive.h5")
        with self._file() as f:
            a = f.attrs
            if _text(a.get("format", "")) != FORMAT:
                raise ValueError(f"{self.archive}: not an sgbem archive (root attribute "
                                 f"format is {_text(a.get('format', ''))!r}, not {FORMAT!r})")
            self.title = _text(a.get("title", ""))
            self.status = _text(a.get("status", ""))
            self._summary_text = _text(a.get("summary", "{}"))
            units = json.loads(_text(a.get("units", "{}")))
            length, force = units.get("length") or "length", units.get("force") or "force"
            self.units = {"length": length, "force": force, "stress": f"{force}/{length}^2"}
            # As the scene gave them ("" where it gave none): the VTK files' texts.
            self._units_given = (units.get("length") or "", units.get("force") or "")
            self._plane = _text(a.get("plane", "strain"))
            self._bodies = self._named(f["bodies"])
            self._interfaces = self._named(f["interfaces"])
            self.bodies = [n for n, _ in self._bodies]
            self.interfaces = [n for n, _ in self._interfaces]
            states = f["states"]
            self.state_count = int(states.attrs["count"])
            self._node_offset = np.asarray(states["node_offset"], dtype=np.int64)
            self._element_offset = np.asarray(states["element_offset"], dtype=np.int64)
            self._pair_offset = np.asarray(states["pair_offset"], dtype=np.int64)

    def __repr__(self):
        return (f"<sgbem.Run {str(self.folder)!r}: {self.title!r}, {self.status}, "
                f"{len(self.bodies)} bodies, {len(self.interfaces)} interfaces, "
                f"{self.state_count} states>")

    def _file(self):
        # HDF5 file locking off, as sgbem itself reads: the archive is never written in place.
        try:
            return h5py.File(self.archive, "r", locking=False)
        except TypeError:  # h5py < 3.5 has no `locking`
            return h5py.File(self.archive, "r")

    @staticmethod
    def _named(group):
        """(real name, group name) of a group's children in the order of its `order`
        attribute (h5py itself lists them alphabetically)."""
        out = []
        for gname in _texts(group.attrs.get("order", [])):
            child = group[gname]
            out.append((_text(child.attrs.get("name", gname)), gname))
        return out

    def _interface(self, name):
        for i, (real, gname) in enumerate(self._interfaces):
            if real == name:
                return i, gname
        known = ", ".join(self.interfaces) or "none"
        raise KeyError(f"{self.archive}: no interface {name!r} (the run has: {known})")

    def _state(self, state):
        n = self.state_count
        k = int(state)
        if not -n <= k < n:
            raise IndexError(f"{self.archive}: state {state} out of range: the run archived "
                             f"{n} states (0 ... {n - 1}, or -1 for the last)")
        return k % n

    @property
    def summary(self):
        """summary.json as a dict (from the archive's copy of it)."""
        return json.loads(self._summary_text)

    @property
    def timings(self):
        """Seconds per stage (dict, run order), as timings.json's `stages`."""
        with self._file() as f:
            g = f["timings"]
            return {n: float(g[n][()]) for n in _texts(g.attrs.get("order", []))}

    @property
    def states(self):
        """One row per archived state (the rows of `pairs(..., state=k)` and
        `to_pyvista(k)`): iteration (the state's number in the run's full history, also with
        history = "steps" or every = n, which keep some of them), load_step, load_factor."""
        rows = []
        with self._file() as f:
            g = f["states"]
            for k in range(self.state_count):
                a = g[f"{k:04}"].attrs
                rows.append((int(a["iteration"]), int(a["load_step"]),
                             float(a["load_factor"]) + 0.0))
        df = pd.DataFrame(rows, columns=["iteration", "load_step", "load_factor"])
        df.index.name = "state"
        df.attrs["units"] = {"iteration": "1", "load_step": "1", "load_factor": "1"}
        return df

    @property
    def history(self):
        """One row per recorded contact state (`/history`: with history = "full" per load
        step its initial status, every contact iteration and the state once the outer
        iterations settle, the rows of `states`; with every = n every n-th of them and the
        last of each step; with "steps" and "final" the last of each load step; none without
        a unilateral interface):
        load_step, iteration, load_factor, solver, and per interface NAME the columns
        `detached_length/NAME`, `open_pairs/NAME`, `closed_pairs/NAME`."""
        with self._file() as f:
            h = f["history"]
            df = pd.DataFrame({
                "load_step": np.asarray(h["load_step"], dtype=np.int64),
                "iteration": np.asarray(h["iteration"], dtype=np.int64),
                "load_factor": _floats(h["load_factor"]),
                "solver": _texts(h["solver"]),
            })
            units = {"load_step": "1", "iteration": "1", "load_factor": "1", "solver": ""}
            rows = len(df)
            detached = _floats(h["detached_length"]).reshape(rows, len(self.interfaces))
            per = h["interfaces"]
            for i, (name, gname) in enumerate(self._history_interfaces(per)):
                pairs = int(self._pair_offset[i + 1] - self._pair_offset[i])
                status = np.asarray(per[gname]["status"]).reshape(rows, pairs)
                df[f"detached_length/{name}"] = detached[:, i]
                df[f"open_pairs/{name}"] = (status == 0).sum(axis=1)
                df[f"closed_pairs/{name}"] = (status == 1).sum(axis=1)
                units[f"detached_length/{name}"] = self.units["length"]
                units[f"open_pairs/{name}"] = "1"
                units[f"closed_pairs/{name}"] = "1"
        df.index.name = "row"
        df.attrs["units"] = units
        return df

    def _history_interfaces(self, group):
        named = self._named(group)
        if [n for n, _ in named] != self.interfaces:
            raise ValueError(f"{self.archive}: /history/interfaces lists "
                             f"{[n for n, _ in named]}, /interfaces {self.interfaces}")
        return named

    def pairs(self, name, state=-1):
        """The contact points of interface `name` at archived state `state` (default the
        last, the final state), one row each, with the columns of interfaces/NAME.csv:
        x, y, s, status ("closed"/"open"), normal_traction, tangential_traction (on the first
        body, tension positive), normal_opening, tangential_slip, gap, and with friction
        tangential_status ("stick"/"slip"/"open") and slip (accumulated path)."""
        i, gname = self._interface(name)
        k = self._state(state)
        lo, hi = self._pair_offset[i], self._pair_offset[i + 1]
        with self._file() as f:
            it = f["interfaces"][gname]
            st = f["states"][f"{k:04}"]
            x = _floats(it["x"]).reshape(-1, 2)
            status = np.asarray(st["status"][lo:hi])
            traction = _floats(st["traction"][lo:hi]).reshape(-1, 2)
            jump = _floats(st["jump"][lo:hi]).reshape(-1, 2)
            df = pd.DataFrame({
                "x": x[:, 0], "y": x[:, 1], "s": _floats(it["s"]),
                "status": [_STATUS.get(int(v), "?") for v in status],
                "normal_traction": traction[:, 1],
                "tangential_traction": traction[:, 0],
                "normal_opening": _floats(st["normal_opening"][lo:hi]),
                "tangential_slip": jump[:, 0],
                "gap": _floats(it["gap"]),
            })
            if "tangential_status" in st:
                ts = np.asarray(st["tangential_status"][lo:hi])
                # -1: no friction at this pair; an open friction pair is "open".
                df["tangential_status"] = [
                    "open" if s == 0 and t != -1 else _TANGENTIAL.get(int(t), "?")
                    for s, t in zip(status, ts)]
                df["slip"] = _floats(st["slip"][lo:hi])
            a = st.attrs
            meta = {"interface": name, "state": k, "iteration": int(a["iteration"]),
                    "load_step": int(a["load_step"]), "load_factor": float(a["load_factor"])}
        length, stress = self.units["length"], self.units["stress"]
        units = {"x": length, "y": length, "s": length, "status": "",
                 "normal_traction": stress, "tangential_traction": stress,
                 "normal_opening": length, "tangential_slip": length, "gap": length,
                 "tangential_status": "", "slip": length}
        df.index.name = "pair"
        df.attrs.update(meta)
        df.attrs["units"] = {c: units[c] for c in df.columns}
        return df

    def contact_points(self, state=-1):
        """Every interface's contact points at archived state `state` (default the last, the
        final state) in one frame, one row per pair, interfaces in run order: the block
        "contact" of the state's multiblock (vtk/contact_NNNN.vtu, NNNN the state), computed
        from the archive. Columns: interface (its name), pair (the row of `pairs(interface)`),
        x, y (the pair's point on the first body), contact_status ("closed"/"open"),
        tangential_status ("stick"/"slip", "open" for an open friction pair, "none" for a
        pair without friction), gap (initial), normal_opening, normal_traction and
        tangential_traction (on the first body, tension positive), normal_force and
        tangential_force (the tractions times the pair's tributary length and the
        thickness: per interface they add up to -N and T of `thrust()`), slip (accumulated
        path, 0 without friction), ux, uy (the first body's displacement at the pair).
        The VTK file's integer codes: contact_status 1 closed, 0 open; tangential_status
        1 stick, 2 slip, 0 open, -1 none."""
        k = self._state(state)
        with self._file() as f:
            st = f["states"][f"{k:04}"]
            thickness = float(f.attrs.get("thickness", 1.0))
            u = _floats(st["u"]).reshape(-1, 2)
            status = np.asarray(st["status"])
            traction = _floats(st["traction"]).reshape(-1, 2)
            opening = _floats(st["normal_opening"])
            total = len(status)
            if "tangential_status" in st:
                ts = np.asarray(st["tangential_status"], dtype=np.int64)
                slip = _floats(st["slip"])
            else:  # no friction in the run
                ts, slip = np.full(total, -1, dtype=np.int64), np.zeros(total)
            parts = {c: [] for c in ("interface", "pair", "x", "y", "gap", "w", "ux", "uy")}
            for i, (name, gname) in enumerate(self._interfaces):
                it = f["interfaces"][gname]
                x = _floats(it["x"]).reshape(-1, 2)
                n = len(x)
                a = int(it.attrs["body_a_index"])
                ua = u[self._node_offset[a] + np.asarray(it["node_a"], dtype=np.int64)]
                parts["interface"].append([name] * n)
                parts["pair"].append(np.arange(n, dtype=np.int64))
                parts["x"].append(x[:, 0])
                parts["y"].append(x[:, 1])
                parts["gap"].append(_floats(it["gap"]))
                parts["w"].append(_tributary(it, x))
                parts["ux"].append(ua[:, 0])
                parts["uy"].append(ua[:, 1])
            a = st.attrs
            meta = {"state": k, "iteration": int(a["iteration"]),
                    "load_step": int(a["load_step"]), "load_factor": float(a["load_factor"])}
        col = {c: np.concatenate(v) if v else np.zeros(0) for c, v in parts.items()}
        if len(col["x"]) != total:
            raise ValueError(f"{self.archive}: state {k} holds {total} pairs, the interfaces "
                             f"{len(col['x'])}")
        w = col["w"] * thickness
        df = pd.DataFrame({
            "interface": pd.Series(col["interface"], dtype=object),
            "pair": col["pair"].astype(np.int64),
            "x": col["x"], "y": col["y"],
            "contact_status": [_STATUS.get(int(v), "?") for v in status],
            "tangential_status": [
                "none" if t == -1 else "open" if s == 0 else _TANGENTIAL.get(int(t), "?")
                for s, t in zip(status, ts)],
            "gap": col["gap"],
            "normal_opening": opening,
            "normal_traction": traction[:, 1],
            "tangential_traction": traction[:, 0],
            "normal_force": traction[:, 1] * w + 0.0,
            "tangential_force": traction[:, 0] * w + 0.0,
            "slip": slip,
            "ux": col["ux"], "uy": col["uy"],
        })
        length, stress, force = self.units["length"], self.units["stress"], self.units["force"]
        df.index.name = "point"
        df.attrs.update(meta)
        df.attrs["units"] = {
            "interface": "", "pair": "1", "x": length, "y": length, "contact_status": "",
            "tangential_status": "", "gap": length, "normal_opening": length,
            "normal_traction": stress, "tangential_traction": stress, "normal_force": force,
            "tangential_force": force, "slip": length, "ux": length, "uy": length}
        return df

    def thrust(self):
        """The thrust line of the final state, one row per joint (interface) in run order,
        with the columns of thrust.csv: joint, body_a, body_b, N (normal force, compression
        positive), T (tangential force on body_a along the pairs' tangent), both times the
        thickness; the point of application x, y and its arc position s; the eccentricity e
        from the joint's mid-point along the joint, e_over_half_length (±1: a hinge at an
        end), inside (within the joint) and in_closed_part (within its closed pairs). A fully
        open joint (N = 0) has no point: NaN and <NA> there. Read from the summary's `thrust`
        block (the archive's copy); an empty frame for a run without interfaces."""
        block = self.summary.get("thrust") or {}
        rows = []
        with self._file() as f:
            for name, gname in self._interfaces:
                a = f["interfaces"][gname].attrs
                t = block.get(name)
                if t is None:
                    continue

                def num(key, t=t):
                    v = t.get(key)
                    return np.nan if v is None else float(v) + 0.0

                rows.append({
                    "joint": name, "body_a": _text(a.get("body_a", "")),
                    "body_b": _text(a.get("body_b", "")),
                    "N": num("normal_force"), "T": num("tangential_force"),
                    "x": num("x"), "y": num("y"), "s": num("s"), "e": num("e"),
                    "e_over_half_length": num("e_over_half_length"),
                    "inside": t.get("inside"), "in_closed_part": t.get("in_closed_part")})
        columns = ["joint", "body_a", "body_b", "N", "T", "x", "y", "s", "e",
                   "e_over_half_length", "inside", "in_closed_part"]
        df = pd.DataFrame(rows, columns=columns)
        for c in ("inside", "in_closed_part"):
            df[c] = df[c].astype("boolean")
        force, length = self.units["force"], self.units["length"]
        df.index.name = "joint_index"
        df.attrs["units"] = {
            "joint": "", "body_a": "", "body_b": "", "N": force, "T": force, "x": length,
            "y": length, "s": length, "e": length, "e_over_half_length": "1", "inside": "",
            "in_closed_part": ""}
        return df

    def hubs(self):
        """The hubs of the final state, one row per body with more than two loaded joints
        that has one, in body order, with the columns of thrust_hubs.csv (docs/thrust.md,
        "Bodies with more joints"): body, x, y (the hub: on the line of action of the
        resultant of the body's group of joints), R_x, R_y (that resultant on the body,
        times the thickness), group ("below": the bed joints below along the body force;
        "above": those above, where none is below), joints (how many loaded joints the hub
        joins, more than two). Computed from the archive's final state as sgbem computes
        thrust_hubs.csv (`_thrust.py`: the same sums in the same order, so the values are
        the file's bit for bit), so an archive copied alone has them too; an empty frame for
        a run without interfaces or without hubs."""
        from ._thrust import hub_rows

        force, length = self.units["force"], self.units["length"]
        units = {"body": "", "x": length, "y": length, "R_x": force, "R_y": force,
                 "group": "", "joints": "1"}
        rows = []
        if self.interfaces and self.state_count > 0:
            with self._file() as f:
                rows = hub_rows(self, f, self.state_count - 1)
        for r in rows:
            r["body"] = self.bodies[r["body"]]
        df = pd.DataFrame({c: pd.Series([r[c] for r in rows],
                                        dtype=object if c in ("body", "group") else
                                        np.int64 if c == "joints" else float)
                           for c in units})
        df.index.name = "hub"
        df.attrs["units"] = units
        return df

    def to_pyvista(self, state=-1):
        """A pyvista MultiBlock of archived state `state` (default the final one): block
        "boundary" (every body's boundary lines at their reference positions, point data
        displacement, traction, contact_status 1 closed 0 open -1 elsewhere,
        normal_traction, body) and, where the run computed the interior field (`field =
        true`, final state only), block "field" (triangles; displacement, stress xx yy xy,
        sxx, syy, sxy, von_mises, body); with interfaces, block "thrust" (the thrust line,
        as the VTK block `thrust`, vtk/thrust_NNNN.vtu: a vertex at each loaded joint's
        point of application with N, T, e, e_over_half_length, inside and in_closed_part
        (1 yes 0 no), joint (the interface's index in `interfaces`) and displacement (the
        first body's at the point); a line through each body between its two loaded joints;
        for a body with more a vertex at its hub, joint -1, NaN and -1 there, and a line
        from each of its joints' points to it; computed from the state's tractions in the
        archive, any state; empty where no joint carries a normal force) and block
        "contact" (a vertex per pair, as the VTK block `contact`: interface and pair
        indices, contact_status 1 closed 0 open, tangential_status 1 stick 2 slip 0 open
        -1 none, gap, normal_opening, the tractions and forces, slip, displacement; the rows
        of `contact_points(state)`); in the final state of a run that failed at a mechanism,
        or of a collapse search, block "mechanism" (the boundary lines with
        mechanism_velocity and body, as the VTK block). The blocks come in the order of
        vtk/state_NNNN.vtm. Warp by `displacement` to see the strained shape, by
        `mechanism_velocity` the mechanism."""
        from ._mesh import (  # pyvista: on demand
            boundary_grid,
            field_grid,
            mechanism_grid,
            thrust_grid,
        )

        k = self._state(state)
        import pyvista

        blocks = pyvista.MultiBlock()
        with self._file() as f:
            blocks["boundary"] = boundary_grid(self, f, k)
            if k == self.state_count - 1 and "interior" in f.get("solution", {}):
                blocks["field"] = field_grid(self, f)
            if self._interfaces:
                blocks["thrust"] = thrust_grid(self, f, k)
            a = f["states"][f"{k:04}"].attrs
            meta = (int(a["iteration"]), int(a["load_step"]), float(a["load_factor"]))
            mechanism = mechanism_grid(self, f) if (
                k == self.state_count - 1 and "mechanism" in f) else None
        if self._interfaces:
            blocks["contact"] = self._contact_block(k)
        if mechanism is not None:
            blocks["mechanism"] = mechanism
        for block in blocks:
            block.field_data["iteration"] = [meta[0]]
            block.field_data["load_step"] = [meta[1]]
            block.field_data["load_factor"] = [meta[2]]
        # The multiblock's own field data, as the .vtm's: title and units as text.
        length, force = self._units_given
        texts = {"run title": self.title, "length unit": length, "force unit": force,
                 "stress unit": f"{force}/{length}^2" if length or force else ""}
        from vtkmodules.vtkCommonCore import vtkStringArray  # with pyvista

        for name, value in texts.items():
            if value:
                # A vtkStringArray of its own: pyvista's setter refuses text that is not
                # ASCII ("Lamé"), which VTK holds as UTF-8 and the .vtm has.
                array = vtkStringArray()
                array.SetName(name)
                array.InsertNextValue(value)
                blocks.GetFieldData().AddArray(array)
        return blocks

    def _contact_block(self, k):
        """The contact points of state `k` as a pyvista PolyData of vertices, with the VTK
        block's integer codes."""
        import pyvista

        df = self.contact_points(k)
        n = len(df)
        points = np.column_stack([df["x"], df["y"], np.zeros(n)])
        poly = pyvista.PolyData(points) if n else pyvista.PolyData()
        index = {name: i for i, (name, _) in enumerate(self._interfaces)}
        codes = {"closed": 1, "open": 0}
        tcodes = {"stick": 1, "slip": 2, "open": 0, "none": -1}
        poly.point_data["interface"] = np.array([index[v] for v in df["interface"]],
                                                dtype=np.int32)
        poly.point_data["pair"] = df["pair"].to_numpy(dtype=np.int32)
        poly.point_data["contact_status"] = np.array(
            [codes[v] for v in df["contact_status"]], dtype=np.int32)
        poly.point_data["tangential_status"] = np.array(
            [tcodes[v] for v in df["tangential_status"]], dtype=np.int32)
        for name in ("gap", "normal_opening", "normal_traction", "tangential_traction",
                     "normal_force", "tangential_force", "slip"):
            poly.point_data[name] = df[name].to_numpy(dtype=float)
        poly.point_data["displacement"] = np.column_stack([df["ux"], df["uy"], np.zeros(n)])
        return poly

