"""pyvista grids of one archived state: the bodies' boundary lines, the interior field and
the thrust line."""

import numpy as np
import pyvista

from ._archive import _floats, _text
from ._thrust import thrust_line


def _grid(points2, cells, cell_type):
    """An UnstructuredGrid of 2D points (z = 0) and cells of one type (n × k indices)."""
    cells = np.asarray(cells, dtype=np.int64).reshape(len(cells), -1)
    points = np.zeros((len(points2), 3))
    points[:, :2] = points2
    flat = np.hstack([np.full((len(cells), 1), cells.shape[1]), cells]).ravel()
    types = np.full(len(cells), cell_type, dtype=np.uint8)
    return pyvista.UnstructuredGrid(flat, types, points)


def _vec3(v2):
    v = np.zeros((len(v2), 3))
    v[:, :2] = v2
    return v


def _boundary_lines(run, f):
    """Every body's boundary nodes (one point per body and node: an interface node appears
    for both of its bodies, so that an opening shows as a gap), elements and body index."""
    points, lines, body = [], [], []
    for b, (_, gname) in enumerate(run._bodies):
        g = f["bodies"][gname]
        nodes = _floats(g["nodes"]).reshape(-1, 2)
        elements = np.asarray(g["elements"], dtype=np.int64).reshape(-1, 2)
        lines.append(elements + run._node_offset[b])
        points.append(nodes)
        body.append(np.full(len(nodes), b, dtype=np.int32))
    points = np.vstack(points) if points else np.zeros((0, 2))
    lines = np.vstack(lines) if lines else np.zeros((0, 2), dtype=np.int64)
    return points, lines, np.concatenate(body) if body else np.zeros(0, np.int32)


def boundary_grid(run, f, k):
    """The boundary lines of every body in state `k`."""
    st = f["states"][f"{k:04}"]
    u = _floats(st["u"]).reshape(-1, 2)
    t = _floats(st["t"]).reshape(-1, 2, 2)
    points, lines, body = _boundary_lines(run, f)
    grid = _grid(points, lines, pyvista.CellType.LINE)
    grid.point_data["displacement"] = _vec3(u)
    # Traction at a node: the average of the element-end values there.
    total, count = np.zeros((len(points), 2)), np.zeros(len(points))
    for end in (0, 1):
        np.add.at(total, lines[:, end], t[:, end, :])
        np.add.at(count, lines[:, end], 1.0)
    grid.point_data["traction"] = _vec3(total / np.maximum(count, 1.0)[:, None])
    status, tn = _interface_nodes(run, f, st, len(points))
    grid.point_data["contact_status"] = status
    grid.point_data["normal_traction"] = tn
    grid.point_data["body"] = body
    return grid


def mechanism_grid(run, f):
    """The mechanism drawn with the final state (/mechanism): every body's boundary lines
    with mechanism_velocity, each moving body's rigid velocity t + w k x (x - c) at its
    nodes (zero on the bodies at rest, the fastest node at 1), as the VTK block."""
    g = f["mechanism"]
    points, lines, body = _boundary_lines(run, f)
    velocity = np.zeros((len(points), 2))
    c = _floats(g["centroid"]).reshape(-1, 2)
    t = _floats(g["translation"]).reshape(-1, 2)
    w = _floats(g["rotation"])
    for i, b in enumerate(np.asarray(g["body"], dtype=np.int64)):
        x = points[body == b]
        velocity[body == b] = np.column_stack([t[i, 0] - w[i] * (x[:, 1] - c[i, 1]),
                                               t[i, 1] + w[i] * (x[:, 0] - c[i, 0])])
    grid = _grid(points, lines, pyvista.CellType.LINE)
    grid.point_data["mechanism_velocity"] = _vec3(velocity)
    grid.point_data["body"] = body
    return grid


def _interface_nodes(run, f, st, n):
    """Per boundary point: the status (1 closed, 0 open, -1 not an interface node) and the
    normal traction of its pair (NaN elsewhere)."""
    status = np.full(n, -1, dtype=np.int32)
    tn = np.full(n, np.nan)
    pair_status = np.asarray(st["status"])
    pair_tn = _floats(st["traction"]).reshape(-1, 2)[:, 1]
    for i, (_, gname) in enumerate(run._interfaces):
        it = f["interfaces"][gname]
        lo, hi = run._pair_offset[i], run._pair_offset[i + 1]
        for side in ("a", "b"):
            body = int(it.attrs[f"body_{side}_index"])
            nodes = np.asarray(it[f"node_{side}"], dtype=np.int64) + run._node_offset[body]
            status[nodes] = pair_status[lo:hi]
            tn[nodes] = pair_tn[lo:hi]
    return status, tn


def field_grid(run, f):
    """The interior field of the final state on every body's triangles."""
    g = f["solution"]["interior"]
    strain = run._plane == "strain"
    points, triangles, columns, body = [], [], {"u": [], "sigma": [], "szz": []}, []
    offset = 0
    for b, (_, gname) in enumerate(run._bodies):
        if gname not in g:
            continue
        gg, bg = g[gname], f["bodies"][gname]
        mesh_nodes = np.asarray(gg["mesh_nodes"], dtype=np.int64)
        local = {int(m): i for i, m in enumerate(mesh_nodes)}
        tri = np.asarray(bg["triangles"], dtype=np.int64).reshape(-1, 3)
        triangles.append(np.vectorize(local.__getitem__, otypes=[np.int64])(tri) + offset
                         if len(tri) else tri)
        points.append(_floats(gg["x"]).reshape(-1, 2))
        sigma = _floats(gg["sigma"]).reshape(-1, 3)
        nu = float(bg.attrs["poisson"])
        columns["u"].append(_floats(gg["u"]).reshape(-1, 2))
        columns["sigma"].append(sigma)
        columns["szz"].append(nu * (sigma[:, 0] + sigma[:, 1]) if strain
                              else np.zeros(len(sigma)))
        body.append(np.full(len(mesh_nodes), b, dtype=np.int32))
        offset += len(mesh_nodes)
    grid = _grid(np.vstack(points), np.vstack(triangles), pyvista.CellType.TRIANGLE)
    sigma, szz = np.vstack(columns["sigma"]), np.concatenate(columns["szz"])
    sxx, syy, sxy = sigma[:, 0], sigma[:, 1], sigma[:, 2]
    grid.point_data["displacement"] = _vec3(np.vstack(columns["u"]))
    grid.point_data["stress"] = sigma
    grid.point_data["sxx"], grid.point_data["syy"], grid.point_data["sxy"] = sxx, syy, sxy
    grid.point_data["von_mises"] = np.sqrt(0.5 * ((sxx - syy) ** 2 + (syy - szz) ** 2
                                                  + (szz - sxx) ** 2) + 3.0 * sxy ** 2)
    grid.point_data["body"] = np.concatenate(body)
    grid.field_data["stress_unit"] = [_text(run.units["stress"])]
    return grid


def thrust_grid(run, f, k):
    """The thrust line of state `k` (`_thrust.thrust_line`): the VTK block "thrust", an
    UnstructuredGrid of vertices (the joints' points of application, the hubs) and lines."""
    t = thrust_line(run, f, k)
    flat = np.array([v for c in t["cells"] for v in (len(c), *c)], dtype=np.int64)
    grid = pyvista.UnstructuredGrid(flat, np.asarray(t["cell_types"], dtype=np.uint8),
                                    _vec3(t["points"]))
    t["displacement"] = _vec3(t["displacement"])
    for name in ("N", "T", "e", "e_over_half_length", "inside", "in_closed_part", "joint",
                 "displacement"):
        if len(t[name]):
            grid.point_data[name] = t[name]
        else:
            # No joint carries a normal force (all open, or unloaded): the arrays are there,
            # empty, as in the VTK file (pyvista's point_data refuses empty arrays).
            grid.GetPointData().AddArray(pyvista.convert_array(t[name], name=name))
    return grid
