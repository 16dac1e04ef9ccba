"""`sgbem schema`: every shipped scene is valid against the JSON Schema it prints, and the
mistakes an editor should mark are not (an unknown key, a word that is not allowed, a
missing required key, a wrong type)."""

import copy
import json
import os
import pathlib
import subprocess
import tomllib

import jsonschema
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
BIN = os.environ.get("SGBEM", str(ROOT / "target/release/sgbem"))


@pytest.fixture(scope="module")
def schema():
    out = subprocess.run([BIN, "schema"], check=True, capture_output=True, text=True).stdout
    s = json.loads(out)
    jsonschema.Draft7Validator.check_schema(s)
    return s


SCENES = sorted((ROOT / "pipelines").glob("*.toml"))


@pytest.mark.parametrize("path", SCENES, ids=[p.stem for p in SCENES])
def test_shipped_scenes_are_valid(schema, path):
    jsonschema.validate(tomllib.loads(path.read_text()), schema)


def test_mistakes_are_marked(schema):
    good = tomllib.loads((ROOT / "pipelines/wall_collapse.toml").read_text())
    jsonschema.validate(good, schema)
    ok = copy.deepcopy(good)
    ok["output"].update(history="full", every=3, vtk="compressed", vtk_fields=["displacement"])
    jsonschema.validate(ok, schema)
    # The mesh may come from --mesh; `between` in a named interface table.
    ok = copy.deepcopy(good)
    ok["defaults"]["interface"].update(initial="open", gap=0.01)
    ok["boundary"] = {"top": {"ux": 0.0, "ty": -1.0}, "side": {"un": 0.0, "tt": 0.5}}
    jsonschema.validate(ok, schema)
    ok = copy.deepcopy(good)
    ok.pop("mesh")
    ok["interface"] = {"joint": {"model": "unilateral", "between": ["a_face", "b_face"]}}
    jsonschema.validate(ok, schema)
    bad = []
    for change in (
        lambda s: s["defaults"]["interface"].update(frition=0.8),   # unknown key
        lambda s: s["defaults"]["interface"].update(tangential="coulomb"),
        lambda s: s["defaults"]["body"].pop("young"),
        lambda s: s["solve"].update(method="fast"),
        lambda s: s["output"].update(vtk="yes"),
        lambda s: s.update(plane="3d"),
        lambda s: s.update(sovle={}),
        lambda s: s["output"].update(history="steps", every=0),
        lambda s: s["output"].update(vtk="zip"),
        lambda s: s["output"].update(vtk_fields=["displacment"]),
        lambda s: s.pop("plane"),
        lambda s: s["defaults"]["interface"].update(between=["a_face", "b_face"]),
        lambda s: s.update(interface={"joint_*": {"model": "unilateral",
                                                  "between": ["a_face", "b_face"]}}),
        # Combinations the reader refuses (tests/schema.rs has them all, with the reader).
        lambda s: s["defaults"]["interface"].pop("friction"),
        lambda s: s["defaults"]["interface"].update(tangential="slide"),
        lambda s: s["defaults"]["interface"].update(model="bonded"),
        lambda s: s["defaults"]["interface"].update(gap=0.01),
        lambda s: s.update(boundary={"top": {"ux": 0.0, "tx": 1.0}}),
        lambda s: s.update(boundary={"top": {"ux": 0.0, "tn": 1.0}}),
        lambda s: s["solve"].update(load_factors=[1.0]),
        lambda s: s["output"].update(history="steps", every=2),
        lambda s: s.update(mesh={"file": "wall.msh", "h": 2.0}),
        lambda s: (s.pop("body", None), s["defaults"].pop("body")),
    ):
        s = copy.deepcopy(good)
        change(s)
        try:
            jsonschema.validate(s, schema)
        except jsonschema.ValidationError:
            continue
        bad.append(s)
    assert not bad, f"accepted: {bad}"
