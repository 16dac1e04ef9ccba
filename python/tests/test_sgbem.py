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
    assert blocks.keys() == ["boundary", "field"]
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


def test_to_pyvista_without_field(wall, beam):
    assert wall.to_pyvista().keys() == ["boundary"]
    first = beam.to_pyvista(0)
    assert first.keys() == ["boundary"]        # the field is computed at the final state only
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
    assert blocks.keys() == ["boundary", "field"] and blocks["field"].n_points > 0
    # A sliding mechanism: exit 3, every output written; the error names the folder.
    with pytest.raises(sgbem.SgbemError) as e:
        sgbem.run(ROOT / "pipelines/incline_block_slides.toml", out=tmp_path / "slides",
                  mesh=mesh("geo/two_blocks.geo", tmp_path))
    assert e.value.returncode == 3 and "slides on interface" in e.value.message
    failed = sgbem.open(e.value.out)
    assert failed.status == "not converged" == failed.summary["status"]
    assert len(failed.pairs("joint")) == failed.summary["interfaces"]["joint"]["pairs"]


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
