"""Tests of the Python package against real runs of the built sgbem (target/release/sgbem):
the runs `beam` and `wall` of conftest.py."""

import json
import pathlib
import subprocess

import h5py
import numpy as np
import pandas as pd
import pytest

import sgbem
from conftest import ROOT, mesh


def csv_table(run, name):
    return pd.read_csv(run.folder / "interfaces" / f"{name}.csv", keep_default_na=False)


def test_summary_is_summary_json(beam, wall):
    for run in (beam, wall):
        assert run.summary == json.loads((run.folder / "summary.json").read_text())
    # The paper's example 2: 33.85 cm detached.
    assert beam.summary["interfaces"]["joint"]["detached_length"] == pytest.approx(33.85, abs=0.01)


def test_history_has_one_row_per_recorded_state(beam, wall):
    for run in (beam, wall):
        h, contact = run.history, run.summary["contact"]
        # Full history: one row per archived state, with the same iteration numbers; each
        # load step adds to the summary's iteration count its initial status (iteration 0)
        # and the state recorded once the outer iterations settle.
        assert len(h) == run.state_count
        assert list(h["iteration"]) == list(run.states["iteration"])
        assert len(h) == contact["iterations"] + 2 * contact["load_steps"]
        assert all(isinstance(s, str) for s in h["solver"])
        assert h.attrs["units"]["load_factor"] == "1"
    h = beam.history
    assert h.attrs["units"]["detached_length/joint"] == "cm"
    # The last row's detached length is the summary's; open pairs grow from none to 89.
    assert h["detached_length/joint"].iloc[-1] == pytest.approx(
        beam.summary["interfaces"]["joint"]["detached_length"], rel=1e-12)
    assert h["open_pairs/joint"].iloc[0] == 0
    assert h["open_pairs/joint"].iloc[-1] == beam.summary["interfaces"]["joint"]["open_pairs"]


def test_pairs_equal_the_interface_csv(beam, wall):
    for run in (beam, wall):
        for name in run.interfaces:
            pairs, table = run.pairs(name), csv_table(run, name)
            assert list(pairs.columns) == list(table.columns)
            for col in table.columns:
                if table[col].dtype == object:
                    assert list(pairs[col]) == list(table[col]), (name, col)
                else:
                    np.testing.assert_array_equal(pairs[col].to_numpy(), table[col].to_numpy(),
                                                  err_msg=f"{name}.{col}")
    p = beam.pairs("joint")
    assert p.attrs["units"]["normal_traction"] == "daN/cm^2"
    assert p.attrs["units"]["x"] == "cm"
    assert (p["status"] == "open").sum() == 89
    # Tension positive: the closed part of the joint is compressed, the resultant balances
    # the summary's.
    assert p.loc[p["status"] == "closed", "normal_traction"].max() <= 0.0
    assert p["normal_traction"].min() == pytest.approx(
        beam.summary["interfaces"]["joint"]["min_normal_traction"], rel=1e-12)


def negative_zeros(values):
    a = np.asarray(values, dtype=float).ravel()
    return int(np.sum((a == 0.0) & np.signbit(a)))


def test_no_negative_zero(wall):
    with h5py.File(wall.archive, "r") as f:  # the archive does hold -0.0
        assert negative_zeros(f["history/detached_length"]) > 0
    assert negative_zeros(wall.history.select_dtypes("float")) == 0
    for state in (0, -1):
        for name in wall.interfaces:
            assert negative_zeros(wall.pairs(name, state=state).select_dtypes("float")) == 0


def test_interface_order_is_the_run_order(wall):
    with h5py.File(wall.archive, "r") as f:
        alphabetical = list(f["interfaces"].keys())
    assert len(wall.bodies) == 13 and len(wall.interfaces) == 26
    # summary.json lists them alphabetically too; the run order is that of `sgbem inspect`.
    assert sorted(wall.interfaces) == list(wall.summary["interfaces"]) != wall.interfaces
    # h5py's listing is not the run order, so reading offsets in its order would be wrong
    # (test_pairs_equal_the_interface_csv checks every interface's pairs on this wall).
    assert alphabetical[0] == "joints[brick_10|brick_11]"
    assert wall.interfaces[0] == "joints[brick_1|brick_2]"
    inspect = subprocess.run([sgbem._cli.executable(), "inspect", str(wall.archive)],
                             capture_output=True, text=True, check=True).stdout
    positions = [inspect.index(name) for name in wall.interfaces]
    assert positions == sorted(positions)


def test_states_and_unknown_names(beam):
    states = beam.states
    assert len(states) == beam.state_count == 91
    assert beam.pairs("joint", state=0).attrs["iteration"] == states["iteration"].iloc[0]
    assert (beam.pairs("joint", state=0)["status"] == "closed").all()
    with pytest.raises(KeyError, match="joint"):
        beam.pairs("joints")
    with pytest.raises(IndexError, match="91 states"):
        beam.pairs("joint", state=91)


def test_to_pyvista_final_state_with_field(beam):
    blocks = beam.to_pyvista()
    assert blocks.keys() == ["boundary", "field", "thrust", "contact"]
    boundary, field = blocks["boundary"], blocks["field"]
    import pyvista
    vtk = pathlib.Path(beam.folder, "vtk")
    last = beam.state_count - 1
    ref_b = pyvista.read(vtk / f"boundary_{last:04}.vtu")
    ref_f = pyvista.read(vtk / f"field_{last:04}.vtu")
    np.testing.assert_allclose(boundary.points, ref_b.points, rtol=0, atol=0)
    for name in ("displacement", "traction", "contact_status", "body"):
        np.testing.assert_allclose(boundary.point_data[name], ref_b.point_data[name],
                                   rtol=1e-12, atol=1e-300, err_msg=name)
    assert field.n_points == ref_f.n_points == 2370
    for name in ("displacement", "sxx", "syy", "sxy", "von_mises"):
        np.testing.assert_allclose(field.point_data[name], ref_f.point_data[name],
                                   rtol=1e-9, atol=1e-12, err_msg=name)
    assert field.n_cells == ref_f.n_cells
    # The contact block: the VTK file's points and arrays, exactly.
    contact, ref_c = blocks["contact"], pyvista.read(vtk / f"contact_{last:04}.vtu")
    assert contact.n_points == ref_c.n_points == 105
    np.testing.assert_array_equal(contact.points, ref_c.points)
    for name in ("interface", "pair", "contact_status", "tangential_status", "gap",
                 "normal_opening", "normal_traction", "tangential_traction", "normal_force",
                 "tangential_force", "slip", "displacement"):
        np.testing.assert_array_equal(contact.point_data[name], ref_c.point_data[name],
                                      err_msg=name)


def test_to_pyvista_without_field(wall, beam):
    assert wall.to_pyvista().keys() == ["boundary", "thrust", "contact"]
    first = beam.to_pyvista(0)
    assert first.keys() == ["boundary", "thrust", "contact"]   # the field: at the final state only
    assert first["boundary"].field_data["iteration"][0] == beam.states["iteration"].iloc[0]


def test_open_the_archive_alone(beam):
    run = sgbem.open(beam.archive)
    assert run.interfaces == ["joint"] and run.bodies == ["A", "B"]
    assert run.summary == beam.summary
    with pytest.raises(FileNotFoundError, match="archive"):
        sgbem.open(beam.folder / "interfaces")


def test_run_overrides_and_errors(beam, tmp_path):
    m = mesh("geo/clamped_beam_joint.geo", tmp_path)
    scene = ROOT / "pipelines/clamped_beam_joint.toml"
    half = sgbem.run(scene, out=tmp_path / "half", mesh=m,
                     set={"boundary.top.ty": -5.0, "solve.method": "lcp"})
    assert half.summary["overrides"] == ["boundary.top.ty=-5.0", 'solve.method="lcp"']
    # Half the load: the same detachment (no gap, no cohesion), half the tractions.
    assert half.summary["interfaces"]["joint"]["detached_length"] == pytest.approx(
        beam.summary["interfaces"]["joint"]["detached_length"], rel=1e-12)
    np.testing.assert_allclose(half.pairs("joint")["normal_traction"],
                               0.5 * beam.pairs("joint")["normal_traction"], rtol=1e-9,
                               atol=1e-9)
    with pytest.raises(sgbem.SgbemError) as e:
        sgbem.run(scene, out=tmp_path / "bad", mesh=m, set={"body.A.poison": 0.2})
    assert e.value.returncode == 2
    assert "body.A.poison" in e.value.message and "poisson" in e.value.message
    assert e.value.out is None


def test_a_run_without_interfaces_and_a_failed_run(tmp_path):
    lame = sgbem.run(ROOT / "pipelines/lame_cylinder.toml", out=tmp_path / "lame",
                     mesh=mesh("geo/lame_cylinder.geo", tmp_path))
    assert lame.interfaces == [] and lame.state_count == 1
    assert len(lame.history) == 0 and list(lame.history.columns) == [
        "load_step", "iteration", "load_factor", "solver"]
    blocks = lame.to_pyvista()
    # No interfaces: neither a thrust line nor contact points, as in vtk/state_0000.vtm.
    assert blocks.keys() == ["boundary", "field"] and blocks["field"].n_points > 0
    import pyvista
    assert pyvista.read(lame.folder / "vtk/state_0000.vtm").keys() == ["boundary", "field"]
    assert len(lame.contact_points()) == 0 and len(lame.hubs()) == 0
    assert list(lame.hubs().columns) == ["body", "x", "y", "R_x", "R_y", "group", "joints"]
    # A sliding mechanism: exit 3, every output written; the error names the folder.
    with pytest.raises(sgbem.SgbemError) as e:
        sgbem.run(ROOT / "pipelines/incline_block_slides.toml", out=tmp_path / "slides",
                  mesh=mesh("geo/two_blocks.geo", tmp_path))
    assert e.value.returncode == 3 and "slides on interface" in e.value.message
    failed = sgbem.open(e.value.out)
    assert failed.status == "not converged" == failed.summary["status"]
    assert len(failed.pairs("joint")) == failed.summary["interfaces"]["joint"]["pairs"]
    # The mechanism: the upper block slides along (1, 0); its block equals the VTK one.
    assert [(b["body"], b["kind"], b["magnitude"]) for b in failed.summary["mechanism"]] == [
        ("upper", "translation", 1.0)]
    last = failed.state_count - 1
    blocks = failed.to_pyvista()
    assert blocks.keys() == ["boundary", "field", "thrust", "contact", "mechanism"]
    assert "mechanism" not in failed.to_pyvista(0).keys()
    pyvista = pytest.importorskip("pyvista")
    vtk = pyvista.read(failed.folder / f"vtk/state_{last:04d}.vtm")["mechanism"]
    for name in ("mechanism_velocity", "body"):
        np.testing.assert_array_equal(blocks["mechanism"].point_data[name], vtk.point_data[name])
    np.testing.assert_array_equal(blocks["mechanism"].points, vtk.points)
    moving = blocks["mechanism"].point_data["mechanism_velocity"]
    assert np.abs(np.linalg.norm(moving, axis=1).max() - 1.0) < 1e-12


def test_steps_history_and_compressed_vtk(tmp_path):
    """history = "steps" keeps the last state of each load step of the full run (the
    incline block: 5 steps), its history one row per step; the compressed VTK files read in
    pyvista to the full run's numbers."""
    pyvista = pytest.importorskip("pyvista")
    m = mesh("geo/two_blocks.geo", tmp_path)
    scene = ROOT / "pipelines/incline_block.toml"
    full = sgbem.run(scene, out=tmp_path / "full", mesh=m)
    steps = sgbem.run(scene, out=tmp_path / "steps", mesh=m,
                      set={"output.history": "steps", "output.vtk": "compressed"})
    last = full.states.groupby("load_step")["iteration"].max()
    assert list(steps.states["load_step"]) == [0, 1, 2, 3, 4]
    assert list(steps.states["iteration"]) == list(last) == [0, 1, 2, 10, 13]
    assert list(steps.history["load_step"]) == [0, 1, 2, 3, 4]
    for k, it in enumerate(last):
        a = pyvista.read(full.folder / f"vtk/boundary_{it:04d}.vtu")
        b = pyvista.read(steps.folder / f"vtk/boundary_{k:04d}.vtu")
        assert "compressor" in (steps.folder / f"vtk/boundary_{k:04d}.vtu").read_text()[:400]
        for name in a.point_data:
            assert np.array_equal(a.point_data[name], b.point_data[name]), (k, name)
    f, s = full.pairs("joint", state=-1), steps.pairs("joint", state=-1)
    pd.testing.assert_frame_equal(f, s)


def test_thrust_equals_thrust_csv(beam, wall):
    for run in (beam, wall):
        df = run.thrust()
        table = pd.read_csv(run.folder / "thrust.csv", keep_default_na=False, na_values=[""])
        units = run.units
        # The CSV's header carries the units; the frame's attrs do.
        assert list(table.columns)[3] == f"N [{units['force']}]"
        table.columns = [c.split(" [")[0] for c in table.columns]
        assert list(df.columns) == list(table.columns)
        assert list(df["joint"]) == run.interfaces        # run order
        for col in ("joint", "body_a", "body_b"):
            assert list(df[col]) == list(table[col])
        for col in ("N", "T", "x", "y", "s", "e", "e_over_half_length"):
            np.testing.assert_array_equal(df[col].to_numpy(), table[col].to_numpy(float),
                                          err_msg=col)
        assert df.attrs["units"]["N"] == units["force"] and df.attrs["units"]["e"] == units["length"]
        # N is the summary's normal resultant (summed element by element there: the same
        # integral to round-off), compression positive.
        for name, n in zip(df["joint"], df["N"]):
            r = run.summary["interfaces"][name]["normal_resultant"]
            assert n == pytest.approx(-r, rel=1e-12, abs=1e-12 * abs(df["N"]).max())
    # Example 2: the joint open over 33.85 cm, the resultant within its closed part.
    t = beam.thrust().iloc[0]
    assert t["N"] > 0 and t["inside"] and t["in_closed_part"]
    assert 0.5 < abs(t["e_over_half_length"]) < 1.0


# Codes of the VTK contact block (src/output/vtk `contact_grid`).
CONTACT_STATUS = {1: "closed", 0: "open"}
TANGENTIAL_STATUS = {1: "stick", 2: "slip", 0: "open", -1: "none"}


def vtk_text(values):
    """Text field data of sgbem's VTK files: UTF-8 bytes in a UInt8 array."""
    return bytes(np.asarray(values, dtype=np.uint8)).decode("utf-8")


def patch_nonmatching(tmp_path):
    """The patch test of tests/geometry_contact.rs: two blocks meshed on their own (10
    elements under the interface, 7 above), on rollers, the top pushed down: an interface
    with `pairing/` in the archive (its pairs weighted by the pairing's weights)."""
    scene = tmp_path / "patch.toml"
    scene.write_text(
        'title = "patch test, independent meshes"\nplane = "strain"\n'
        f'[mesh]\nfile = "{ROOT / "geo/patch_nonmatching.geo"}"\nn_lower = 10\nn_upper = 7\n'
        "[body.upper]\nyoung = 1000.0\npoisson = 0.3\n"
        "[body.lower]\nyoung = 3000.0\npoisson = 0.2\n"
        "[boundary.top]\nuy = -0.01\ntx = 0.0\n[boundary.base]\nuy = 0.0\ntx = 0.0\n"
        "[boundary.left]\nux = 0.0\nty = 0.0\n[boundary.right]\nux = 0.0\nty = 0.0\n"
        '[interface.contact]\nmodel = "unilateral"\ninitial = "open"\ntangential = "stick"\n'
        "[solve]\ntolerance = 1e-10\n")
    return sgbem.run(scene, out=tmp_path / "patch")


@pytest.fixture(scope="module")
def patch(tmp_path_factory):
    return patch_nonmatching(tmp_path_factory.mktemp("patch"))


def check_contact_points(run):
    """contact_points() of the final state against the interface tables, pairs() and
    thrust(), interface by interface."""
    df = run.contact_points()
    assert len(df) == run.summary["counts"]["interface_pairs"]
    assert list(df["interface"].unique()) == run.interfaces        # run order
    thrust = run.thrust().set_index("joint")
    same = {"x": "x", "y": "y", "contact_status": "status", "gap": "gap",
            "normal_opening": "normal_opening", "normal_traction": "normal_traction",
            "tangential_traction": "tangential_traction"}
    for name, rows in df.groupby("interface", sort=False):
        table, pairs = csv_table(run, name), run.pairs(name)
        assert list(rows["pair"]) == list(range(len(table))) == list(pairs.index)
        friction = "tangential_status" in table.columns
        columns = dict(same, **({"tangential_status": "tangential_status", "slip": "slip"}
                                if friction else {}))
        for ours, theirs in columns.items():
            for other in (table[theirs], pairs[theirs]):
                if other.dtype == object:
                    assert list(rows[ours]) == list(other), (name, ours)
                else:
                    np.testing.assert_array_equal(rows[ours].to_numpy(), other.to_numpy(),
                                                  err_msg=f"{name}.{ours}")
        if not friction:
            assert (rows["tangential_status"] == "none").all() and (rows["slip"] == 0).all()
        # Per joint the pairs' forces add up to the thrust line's resultants (docs/thrust.md).
        fn, ft = rows["normal_force"], rows["tangential_force"]
        n, t = thrust.loc[name, "N"], thrust.loc[name, "T"]
        assert fn.sum() == pytest.approx(-n, rel=0, abs=1e-12 * max(fn.abs().sum(), 1e-300))
        assert ft.sum() == pytest.approx(t, rel=0, abs=1e-12 * max(ft.abs().sum(), 1e-300))
        assert (fn[rows["contact_status"] == "open"] == 0).all()      # no cohesion here
    return df


def test_contact_points_equal_the_interface_tables_and_the_thrust(beam, wall):
    for run in (beam, wall):
        df = check_contact_points(run)
        assert df.attrs["state"] == run.state_count - 1
        assert df.attrs["iteration"] == run.states["iteration"].iloc[-1]
    p = beam.contact_points()
    assert p.attrs["units"]["normal_force"] == "daN" and p.attrs["units"]["gap"] == "cm"
    assert (p["contact_status"] == "open").sum() == 89 and set(p["interface"]) == {"joint"}
    w = wall.contact_points()
    assert len(w) == 182 and (w["tangential_status"] == "slip").sum() >= 1
    assert negative_zeros(w.select_dtypes("float")) == 0


def test_contact_points_equal_the_vtk_contact_block(beam, wall, patch):
    """Every column, bit for bit, against block "contact" of the state's multiblock
    (vtk/state_NNNN.vtm, read by pyvista), at the first and the last state; also where the
    sides were meshed on their own (the pairs' tributary lengths from the pairing)."""
    pyvista = pytest.importorskip("pyvista")
    with h5py.File(patch.archive, "r") as f:
        assert "pairing" in f["interfaces"][patch.interfaces[0]]
    check_contact_points(patch)
    for run in (beam, wall, patch):
        for state in sorted({0, run.state_count - 1}):
            df = run.contact_points(state)
            blocks = pyvista.read(run.folder / f"vtk/state_{state:04d}.vtm")
            vtk = blocks["contact"]
            names = vtk_text(vtk.field_data["interface_names"]).split("\n")
            assert names == run.interfaces
            assert vtk.n_points == len(df)
            d = vtk.point_data
            assert [names[i] for i in d["interface"]] == list(df["interface"])
            assert [CONTACT_STATUS[v] for v in d["contact_status"]] == list(df["contact_status"])
            assert [TANGENTIAL_STATUS[v] for v in d["tangential_status"]] == list(
                df["tangential_status"])
            for col in ("pair", "gap", "normal_opening", "normal_traction",
                        "tangential_traction", "normal_force", "tangential_force", "slip"):
                np.testing.assert_array_equal(d[col], df[col].to_numpy(), err_msg=col)
            for j, (p, u) in enumerate((("x", "ux"), ("y", "uy"))):
                np.testing.assert_array_equal(vtk.points[:, j], df[p].to_numpy())
                np.testing.assert_array_equal(d["displacement"][:, j], df[u].to_numpy())
    # The patch test's exact state: the oedometric pressure on every pair, p over the
    # interface's length 2 (tests/geometry_contact.rs).
    def oedometric(e, nu):
        return e * (1 - nu) / ((1 + nu) * (1 - 2 * nu))

    p = 0.01 / (1 / oedometric(1000.0, 0.3) + 1 / oedometric(3000.0, 0.2))
    c = patch.contact_points()
    assert len(c) == 8 and (c["contact_status"] == "closed").all()
    assert c["normal_force"].sum() == pytest.approx(-2 * p, rel=1e-8)


def assert_hubs_equal_the_csv(run):
    """`run.hubs()` (computed from the archive) against the run folder's thrust_hubs.csv:
    the same rows, names and numbers bit for bit (the file writes round-tripping decimals)."""
    hubs = run.hubs()
    table = pd.read_csv(run.folder / "thrust_hubs.csv", keep_default_na=False)
    assert list(table.columns) == ["body", "x [m]", "y [m]", "R_x [kN]", "R_y [kN]", "group",
                                   "joints"]
    assert list(hubs.columns) == [c.split(" [")[0] for c in table.columns]
    assert hubs.attrs["units"] == {"body": "", "x": "m", "y": "m", "R_x": "kN", "R_y": "kN",
                                   "group": "", "joints": "1"}
    assert len(hubs) == len(table)
    for col in ("body", "group"):
        assert list(hubs[col]) == list(table[col].astype(str))
    for col, head in zip(("x", "y", "R_x", "R_y"), table.columns[1:5]):
        np.testing.assert_array_equal(hubs[col].to_numpy(), table[head].to_numpy(dtype=float),
                                      err_msg=col)
    assert list(hubs["joints"]) == list(table["joints"])
    return hubs


def test_hubs_equal_thrust_hubs_csv(beam, wall, collapse, tmp_path):
    beam_hubs = beam.hubs()                       # one joint, two bodies: no hub
    assert len(beam_hubs) == 0 and list(beam_hubs.columns) == [
        "body", "x", "y", "R_x", "R_y", "group", "joints"]
    assert beam_hubs["joints"].dtype == np.int64 and beam_hubs["x"].dtype == float
    assert len(pd.read_csv(beam.folder / "thrust_hubs.csv")) == 0
    # The collapse search's state: body forces of its own (sideways), its hubs' "down".
    # (7 bricks with the full rows, its default, at t = 0.711; brick_4 has two loaded joints
    # there. The evolutive path stands only to 0.484, with 8.)
    assert len(assert_hubs_equal_the_csv(collapse)) == 7
    hubs = assert_hubs_equal_the_csv(wall)
    # A hub per brick of the 3 x 4 bond but the last of the top course (its head joint
    # opens: two loaded joints); in body order, each joining the body's loaded joints of
    # thrust(), more than two.
    assert len(hubs) == 12 and hubs["joints"].dtype == np.int64
    positions = [wall.bodies.index(b) for b in hubs["body"]]
    assert positions == sorted(positions)
    loaded = wall.thrust().dropna(subset=["x"])
    for body, joints in zip(hubs["body"], hubs["joints"]):
        assert joints == ((loaded["body_a"] == body) | (loaded["body_b"] == body)).sum() > 2
    # Straight beds: the hub lies on the body's bed, the first course's (resting on the
    # clamped base, no joint below) on its top bed, the others' on their bottom bed, where
    # the bed joints below carry the brick (R_y > 0) or, above the first course, press it.
    with h5py.File(wall.archive, "r") as f:
        for _, h in hubs.iterrows():
            gname = dict(wall._bodies)[h["body"]]
            nodes = np.asarray(f["bodies"][gname]["nodes"])
            bed = nodes[:, 1].min() if h["group"] == "below" else nodes[:, 1].max()
            assert h["y"] == pytest.approx(bed, abs=1e-12)
            assert nodes[:, 0].min() <= h["x"] <= nodes[:, 0].max()
            assert (h["R_y"] > 0) == (h["group"] == "below")
    # The final state's VTK thrust block holds the same hubs (joint -1), bit for bit.
    pyvista = pytest.importorskip("pyvista")
    last = wall.state_count - 1
    thrust = pyvista.read(wall.folder / f"vtk/state_{last:04d}.vtm")["thrust"]
    at = thrust.points[thrust.point_data["joint"] == -1]
    np.testing.assert_array_equal(at[:, :2], hubs[["x", "y"]].to_numpy())
    # An archive copied alone: the same hubs (computed from it), the contact points too.
    alone = tmp_path / "archive.h5"
    alone.write_bytes(wall.archive.read_bytes())
    run = sgbem.open(alone)
    pd.testing.assert_frame_equal(run.hubs(), hubs)
    pd.testing.assert_frame_equal(run.contact_points(), wall.contact_points())


def test_to_pyvista_thrust_block_equals_the_vtk_thrust_block(beam, wall, collapse, patch):
    """Block "thrust" of every archived state against vtk/thrust_NNNN.vtu read by pyvista,
    exactly: points, cells and every point array (NaN at the hubs); the blocks in the order
    of the state's multiblock. At the final state its joints' points are thrust()'s and its
    hubs hubs()'s. The collapse search's state has body forces of its own (sideways 20 t):
    the hubs' "down" is theirs, not the bodies' attribute's. The patch test (sides meshed on
    their own, initially open) starts without a loaded joint: an empty block, as its file."""
    pyvista = pytest.importorskip("pyvista")
    for run in (beam, wall, collapse, patch):
        vtk = pathlib.Path(run.folder, "vtk")
        for k in range(run.state_count):
            blocks = run.to_pyvista(k)
            vtm = pyvista.read(vtk / f"state_{k:04d}.vtm")
            assert blocks.keys() == vtm.keys()
            # Title and units as text in the multiblock's field data, as the .vtm's.
            texts = {n: list(vtm.field_data[n]) for n in vtm.field_data}
            assert {n: list(blocks.field_data[n]) for n in blocks.field_data} == texts
            assert "run title" in texts
            if run is beam:
                assert texts == {"run title": [run.title], "length unit": ["cm"],
                                 "force unit": ["daN"], "stress unit": ["daN/cm^2"]}
            ours, ref = blocks["thrust"], pyvista.read(vtk / f"thrust_{k:04d}.vtu")
            assert ours.n_points == ref.n_points and ours.n_cells == ref.n_cells, k
            np.testing.assert_array_equal(ours.points, ref.points)
            np.testing.assert_array_equal(ours.cells, ref.cells)
            np.testing.assert_array_equal(ours.celltypes, ref.celltypes)
            assert list(ours.point_data) == list(ref.point_data) == [
                "N", "T", "e", "e_over_half_length", "inside", "in_closed_part", "joint",
                "displacement"]
            for name in ref.point_data:
                assert ours.point_data[name].dtype == ref.point_data[name].dtype, name
                np.testing.assert_array_equal(ours.point_data[name], ref.point_data[name],
                                              err_msg=f"state {k}: {name}")
            assert ours.field_data["iteration"][0] == run.states["iteration"].iloc[k]
        # The final state: a point per loaded joint (thrust(), from the summary), then the
        # hubs (hubs(), equal to thrust_hubs.csv).
        d = ours.point_data
        at = d["joint"] >= 0
        loaded = run.thrust().dropna(subset=["x"])
        assert [run.interfaces[j] for j in d["joint"][at]] == list(loaded["joint"])
        for col in ("N", "T", "e", "e_over_half_length"):
            np.testing.assert_array_equal(d[col][at], loaded[col].to_numpy(), err_msg=col)
        np.testing.assert_array_equal(ours.points[at, :2], loaded[["x", "y"]].to_numpy())
        assert list(d["inside"][at]) == [int(v) for v in loaded["inside"]]
        assert list(d["in_closed_part"][at]) == [int(v) for v in loaded["in_closed_part"]]
        hubs = run.hubs()
        np.testing.assert_array_equal(ours.points[~at, :2], hubs[["x", "y"]].to_numpy())
        assert (d["inside"][~at] == -1).all() and np.isnan(d["N"][~at]).all()
        # A vertex per point; a line through each body with two loaded joints and from each
        # hub to each of its joints' points.
        types = list(ours.celltypes)
        per_body = pd.concat([loaded["body_a"], loaded["body_b"]]).value_counts()
        assert types.count(pyvista.CellType.VERTEX) == ours.n_points
        assert types.count(pyvista.CellType.LINE) == (per_body == 2).sum() + hubs["joints"].sum()
    assert beam.to_pyvista()["thrust"].n_points == 1               # one joint, no hub
    assert patch.to_pyvista(0)["thrust"].n_points == 0 < patch.to_pyvista()["thrust"].n_points
    assert len(wall.hubs()) == 12 and len(collapse.hubs()) == 7
    with h5py.File(collapse.archive, "r") as f:
        own = np.asarray(f["states/0000/body_force"])
        brick = np.asarray(f["bodies"][collapse._bodies[0][1]].attrs["body_force"])
    assert own[0, 1] == brick[1] == -20.0 and 0 < own[0, 0] < brick[0] == 20.0
