"""Cross-check sgbem's mesh reading against meshio, an independent MSH reader.

For every mesh given that has a scene of the same name in pipelines/, run `sgbem check` and
compare its counts with what meshio reads from the same file:
  boundary elements = line elements of the bodies + those of interface curves once more
                      (an interface node pair is duplicated per body);
  interface pairs   = interface line elements + 1 per interface (one open chain each).
Interface curves are those the scene's [interface] tables name or match (fnmatch on glob
tables such as "joint*"), and, with [defaults.interface], every other Physical Curve not in
[boundary] whose line elements are edges of triangles of two Physical Surfaces. A curve that
joins several pairs of bodies counts one interface per pair (sgbem splits it). A scene with
[contact] finds further interfaces from the geometry (facing curves of bodies drawn on their
own): its pairs are not counted here (tests/geometry_contact.rs checks them), only its
elements and triangles; so with an interface `between` two such curves.
Usage: check_meshes.py SGBEM MESH...
"""
import pathlib
import fnmatch
import re
import subprocess
import sys
import tomllib

import meshio
import numpy as np


def edge_owners(m):
    """Mesh edge (two node ids) -> the Physical Surfaces of the triangles that have it."""
    owners = {}
    for block, phys in zip(m.cells, m.cell_data["gmsh:physical"]):
        if block.type != "triangle":
            continue
        for tri, tag in zip(block.data, phys):
            for a, b in ((tri[0], tri[1]), (tri[1], tri[2]), (tri[2], tri[0])):
                owners.setdefault(frozenset((a, b)), set()).add(int(tag))
    return {e: frozenset(s) for e, s in owners.items()}


def main():
    sgbem, meshes = sys.argv[1], sys.argv[2:]
    checked = 0
    for path in map(pathlib.Path, meshes):
        scene = pathlib.Path("pipelines") / (path.stem + ".toml")
        if not scene.exists():
            continue
        m = meshio.read(path)
        spec = tomllib.loads(scene.read_text())
        names = {name: tag for name, (tag, dim) in m.field_data.items() if dim == 1}
        owners = edge_owners(m)
        tables = spec.get("interface", {})
        listed = [n for n in names if any(fnmatch.fnmatchcase(n, t) for t in tables)]
        lines = 0
        iface_lines = {}  # (curve tag, the two surfaces' tags) -> line elements
        for block, phys in zip(m.cells, m.cell_data["gmsh:physical"]):
            if block.type != "line":
                continue
            lines += len(block.data)
            for edge, tag in zip(block.data, phys):
                surfaces = owners.get(frozenset(edge), frozenset())
                name = next(n for n, t in names.items() if t == tag)
                default = ("interface" in spec.get("defaults", {})
                           and name not in spec.get("boundary", {}) and len(surfaces) == 2)
                if name in listed or default:
                    key = (int(tag), surfaces)
                    iface_lines[key] = iface_lines.get(key, 0) + 1
        expect_elements = lines + sum(iface_lines.values())
        expect_pairs = sum(n + 1 for n in iface_lines.values())
        triangles = sum(len(b.data) for b in m.cells if b.type == "triangle")

        out = subprocess.run([sgbem, "check", str(scene), "--mesh", str(path)],
                             capture_output=True, text=True)
        assert out.returncode == 0, f"sgbem check {scene} failed:\n{out.stderr}"
        got_elements = int(re.search(r"^boundary elements (\d+)", out.stdout, re.M).group(1))
        got_pairs = sum(int(x) for x in re.findall(r"elements, (\d+) pairs", out.stdout))
        got_triangles = sum(int(x) for x in re.findall(r"; (\d+) triangles", out.stdout))
        # [contact] cuts elements that face two bodies: each cut adds one line element.
        cuts = re.search(r"^\s+(\d+) cuts by \[contact\]", out.stdout, re.M)
        expect_elements += int(cuts.group(1)) if cuts else 0
        assert got_elements == expect_elements, (path, got_elements, expect_elements)
        drawn = "contact" in spec or any("between" in t for t in tables.values())
        if not drawn:
            assert got_pairs == expect_pairs, (path, got_pairs, expect_pairs)
        assert got_triangles == triangles, (path, got_triangles, triangles)
        print(f"check_meshes: {path}: {got_elements} boundary elements, {got_pairs} pairs, "
              f"{got_triangles} triangles — agree with meshio")
        checked += 1
    assert checked > 0, "no mesh with a scene was checked"


if __name__ == "__main__":
    main()
