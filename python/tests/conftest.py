"""Runs of the built sgbem (target/release/sgbem, or $SGBEM) shared by the tests.

The scenes are the shipped ones, meshed here with gmsh into a temporary folder:
clamped_beam_joint (the paper's example 2: one joint, interior field) and a running-bond
wall of 3 courses of 4 bricks (13 bodies, friction, no interior field, 26 split interfaces
whose run order is not the alphabetical order h5py lists them in: brick_10 before brick_2;
the evolutive path, every iteration archived); the collapse search on a wall of 3 courses of
3 bricks (the full rows, its default: one archived state, whose body forces, 20 t sideways at
the multiplier t found, differ from the bodies' own)."""

import pathlib
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))

import sgbem  # noqa: E402


def mesh(geo, dest, *params):
    out = dest / (pathlib.Path(geo).stem + ".msh")
    subprocess.run(["gmsh", "-2", "-format", "msh41", *params, str(ROOT / geo), "-o", str(out)],
                   check=True, capture_output=True)
    return out


@pytest.fixture(scope="session")
def beam(tmp_path_factory):
    d = tmp_path_factory.mktemp("beam")
    return sgbem.run(ROOT / "pipelines/clamped_beam_joint.toml", out=d / "run",
                     mesh=mesh("geo/clamped_beam_joint.geo", d))


@pytest.fixture(scope="session")
def wall(tmp_path_factory):
    d = tmp_path_factory.mktemp("wall")
    # The evolutive path (the wall's default is the full rows: its joints meet at
    # junctions), so that the history holds every iteration.
    return sgbem.run(ROOT / "pipelines/wall_running_bond.toml", out=d / "run",
                     set={"mesh.courses": 3, "mesh.bricks": 4}, method="lcp")




@pytest.fixture(scope="session")
def collapse(tmp_path_factory):
    d = tmp_path_factory.mktemp("collapse")
    return sgbem.run(ROOT / "pipelines/wall_collapse.toml", out=d / "run",
                     set={"mesh.courses": 3, "mesh.bricks": 3,
                          "solve.collapse.tolerance": 0.01})
