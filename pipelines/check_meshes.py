"""Cross-check sgbem's mesh reading against meshio, an independent MSH reader.

For every mesh given that has a scene of the same name in pipelines/, run `sgbem check` and
compare its counts with what meshio reads from the same file:
  boundary elements = line elements of the bodies + those of interface curves once more
                      (an interface node pair is duplicated per body);
  interface pairs   = interface line elements + 1 per interface (one open chain each).
Usage: check_meshes.py SGBEM MESH...
"""
import pathlib
import re
import subprocess
import sys
import tomllib

import meshio
import numpy as np


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
        interfaces = [names[n] for n in spec.get("interface", {})]
        lines = 0
        iface_lines = {tag: 0 for tag in interfaces}
        for block, phys in zip(m.cells, m.cell_data["gmsh:physical"]):
            if block.type != "line":
                continue
            lines += len(block.data)
            for tag in interfaces:
                iface_lines[tag] += int(np.sum(phys == tag))
        expect_elements = lines + sum(iface_lines.values())
        expect_pairs = sum(n + 1 for n in iface_lines.values())
        triangles = sum(len(b.data) for b in m.cells if b.type == "triangle")

        out = subprocess.run([sgbem, "check", str(scene), "--mesh", str(path)],
                             capture_output=True, text=True)
        assert out.returncode == 0, f"sgbem check {scene} failed:\n{out.stderr}"
        got_elements = int(re.search(r"^boundary elements (\d+)", out.stdout, re.M).group(1))
        got_pairs = sum(int(x) for x in re.findall(r"elements, (\d+) pairs", out.stdout))
        got_triangles = sum(int(x) for x in re.findall(r"; (\d+) triangles", out.stdout))
        assert got_elements == expect_elements, (path, got_elements, expect_elements)
        assert got_pairs == expect_pairs, (path, got_pairs, expect_pairs)
        assert got_triangles == triangles, (path, got_triangles, triangles)
        print(f"check_meshes: {path}: {got_elements} boundary elements, {got_pairs} pairs, "
              f"{got_triangles} triangles — agree with meshio")
        checked += 1
    assert checked > 0, "no mesh with a scene was checked"


if __name__ == "__main__":
    main()
