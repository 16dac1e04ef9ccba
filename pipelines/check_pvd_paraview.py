"""Loads a run's vtk/history.pvd in ParaView (pvpython) and checks what a ParaView user sees.

Usage: xvfb-run -a pvpython pipelines/check_pvd_paraview.py RUN_DIR

Checks, at every time of history.pvd: two blocks (boundary, interior field), or the
boundary alone for a run without an interior field; the field block has `stress` as a
6-component symmetric tensor (components XX YY ZZ XY YZ XZ) and the scalars sxx, syy, sxy
that equal its components; every block carries the title and units as field data; the
boundary's `iteration` field data increases with time; the times increase. Then states.pvd:
the same times, at each a multiblock whose field data holds the title and units as text
(string arrays `run title`, `length unit`, `force unit`, `stress unit`, as ParaView's
Information panel lists them) with a block named "boundary", only in a state
that has its interior field (the final one, where computed) a block named "field", and
where the run has interfaces a block named "thrust" (the thrust line: a vertex per joint
that carries a normal force, with N, T and e, and lines through the bodies), and where the
run failed at a mechanism or its collapse search found one (a file mechanism_NNNN.vtu), in
the last state only a block named "mechanism": the boundary's points with the 3-component
`mechanism_velocity`, whose largest magnitude is 1.
Prints one line per check group; exits 1 on the first failure.
"""
import os
import sys

from paraview import servermanager
from paraview.simple import PVDReader
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonDataModel import vtkCompositeDataSet


def fail(msg):
    print(f"check_pvd_paraview: FAIL: {msg}")
    sys.exit(1)


def text(block, name):
    """Text field data: UTF-8 bytes in a UInt8 array."""
    arr = block.GetFieldData().GetArray(name)
    if arr is None:
        fail(f"field data `{name}` missing")
    return bytes(int(arr.GetValue(i)) for i in range(arr.GetNumberOfTuples())).decode()


def number(block, name):
    arr = block.GetFieldData().GetArray(name)
    if arr is None:
        fail(f"field data `{name}` missing")
    return arr.GetValue(0)


def named_leaves(obj, name=None):
    """(block name, dataset) of every leaf (a plain grid: one leaf named None)."""
    if obj is None:
        return []
    if obj.IsA("vtkMultiBlockDataSet"):
        out = []
        for i in range(obj.GetNumberOfBlocks()):
            meta = obj.GetMetaData(i) if obj.HasMetaData(i) else None
            key = vtkCompositeDataSet.NAME()
            out.extend(named_leaves(obj.GetBlock(i),
                                    meta.Get(key) if meta is not None and meta.Has(key) else None))
        return out
    return [(name, obj)]


def leaves(obj):
    return [b for _, b in named_leaves(obj)]


def check_mechanism(pvd, t, named):
    """The mechanism block: as many points as the boundary, `mechanism_velocity` a vector
    whose largest magnitude is 1."""
    blocks = dict(named)
    v = blocks["mechanism"].GetPointData().GetArray("mechanism_velocity")
    if v is None or v.GetNumberOfComponents() != 3:
        fail(f"{pvd} at time {t}: the mechanism block has no 3-component mechanism_velocity")
    if blocks["mechanism"].GetNumberOfPoints() != blocks["boundary"].GetNumberOfPoints():
        fail(f"{pvd} at time {t}: the mechanism block's points are not the boundary's")
    top = float((vtk_to_numpy(v) ** 2).sum(axis=1).max() ** 0.5)
    if abs(top - 1.0) > 1e-12:
        fail(f"{pvd} at time {t}: the largest mechanism_velocity is {top}, not 1")


# The multiblock's own text field data (string arrays) and the blocks' UInt8 array it repeats.
TEXTS = {"run title": "title", "length unit": "length_unit", "force unit": "force_unit",
         "stress unit": "stress_unit"}


def check_text(pvd, t, reader, data, boundary):
    """Title and units as text where ParaView shows them: string arrays in the multiblock's
    field data, equal to the boundary's UInt8 texts, and in the reader's data information
    (what the Information panel lists) as string values, not as a range of byte codes."""
    fd = data.GetFieldData()
    info = reader.GetDataInformation().DataInformation.GetFieldDataInformation()
    for name, bytes_name in TEXTS.items():
        # An empty text is left out of both (a scene without units).
        want = text(boundary, bytes_name) \
            if boundary.GetFieldData().GetArray(bytes_name) is not None else ""
        if not want:
            continue
        a = fd.GetAbstractArray(name)
        if a is None or not a.IsA("vtkStringArray") or a.GetNumberOfValues() != 1:
            fail(f"{pvd} at time {t}: no string array `{name}` in the multiblock's field data")
        if a.GetValue(0) != want:
            fail(f"{pvd} at time {t}: `{name}` is {a.GetValue(0)!r}, the blocks' text {want!r}")
        ai = info.GetArrayInformation(name)
        shown = [ai.GetStringValue(i) for i in range(ai.GetNumberOfStringValues())] \
            if ai is not None else []
        if shown != [want]:
            fail(f"{pvd} at time {t}: ParaView's information on `{name}` shows {shown}, "
                 f"not [{want!r}]")


def check_states(run, times, with_field, with_thrust, with_mechanism):
    """states.pvd: one multiblock per time, named blocks, the field only at the last time,
    the thrust line and the contact rows at every time where the run has interfaces, the
    mechanism at the last time where the run has one."""
    pvd = os.path.join(run, "vtk", "states.pvd")
    reader = PVDReader(FileName=pvd)
    reader.UpdatePipelineInformation()
    if list(reader.TimestepValues) != times:
        fail(f"{pvd}: times differ from history.pvd's")
    for k, t in enumerate(times):
        reader.UpdatePipeline(t)
        data = servermanager.Fetch(reader)
        named = named_leaves(data)
        check_text(pvd, t, reader, data, dict(named)["boundary"])
        want = ["boundary", "field"] if with_field and k == len(times) - 1 else ["boundary"]
        want += ["thrust", "contact"] if with_thrust else []
        want += ["mechanism"] if with_mechanism and k == len(times) - 1 else []
        if [n for n, _ in named] != want:
            fail(f"{pvd} at time {t}: blocks {[n for n, _ in named]}, want {want}")
        for n, b in named:
            if n != "thrust" and b.GetNumberOfPoints() == 0:
                fail(f"{pvd} at time {t}: empty block {n}")
            if n == "thrust" and b.GetPointData().GetArray("N") is None:
                fail(f"{pvd} at time {t}: the thrust block has no N")
            if n == "contact" and b.GetPointData().GetArray("contact_status") is None:
                fail(f"{pvd} at time {t}: the contact block has no contact_status")
            if n == "mechanism":
                check_mechanism(pvd, t, named)
    print(f"check_pvd_paraview: {pvd}: {len(times)} multiblocks, block boundary at every "
          f"time, field {'at the last time only' if with_field else 'nowhere'}, thrust "
          f"{'at every time' if with_thrust else 'nowhere (no interfaces)'}, contact rows "
          f"{'at every time' if with_thrust else 'nowhere'}, title and units as text, "
          f"mechanism {'at the last time only' if with_mechanism else 'nowhere'}: ok")


def main():
    run = sys.argv[1]
    files = os.listdir(os.path.join(run, "vtk"))
    with_field = any(f.startswith("field_") for f in files)
    with_thrust = any(f.startswith("thrust_") for f in files)
    with_mechanism = any(f.startswith("mechanism_") for f in files)
    pvd = os.path.join(run, "vtk", "history.pvd")
    reader = PVDReader(FileName=pvd)
    reader.UpdatePipelineInformation()
    times = list(reader.TimestepValues)
    if not times:
        fail("no times in the series")
    if any(b <= a for a, b in zip(times, times[1:])):
        fail(f"times do not increase: {times}")
    last_iteration = -1.0
    for t in times:
        reader.UpdatePipeline(t)
        blocks = leaves(servermanager.Fetch(reader))
        kinds = {}
        for b in blocks:
            pd = b.GetPointData()
            kinds["field" if pd.GetArray("stress") is not None else "boundary"] = b
        want = {"boundary", "field"} if with_field else {"boundary"}
        if set(kinds) != want:
            fail(f"time {t}: blocks {sorted(kinds)}, want {sorted(want)}")
        for kind, b in kinds.items():
            if not text(b, "title"):
                fail(f"time {t}: {kind} has an empty title")
            if not text(b, "length_unit") or not text(b, "stress_unit"):
                fail(f"time {t}: {kind} has no units")
        it = number(kinds["boundary"], "iteration")
        if it <= last_iteration:
            fail(f"time {t}: iteration {it} after {last_iteration}")
        last_iteration = it
        if not with_field:
            continue
        f = kinds["field"]
        if f.GetNumberOfPoints() == 0 or f.GetNumberOfCells() == 0:
            fail(f"time {t}: empty field block")
        s = f.GetPointData().GetArray("stress")
        if s.GetNumberOfComponents() != 6:
            fail(f"time {t}: stress has {s.GetNumberOfComponents()} components, want 6")
        names = [s.GetComponentName(i) for i in range(6)]
        if names != ["XX", "YY", "ZZ", "XY", "YZ", "XZ"]:
            fail(f"time {t}: stress component names {names}")
        tensor = vtk_to_numpy(s)
        for col, name in [(0, "sxx"), (1, "syy"), (3, "sxy")]:
            arr = f.GetPointData().GetArray(name)
            if arr is None:
                fail(f"time {t}: scalar {name} missing")
            if (vtk_to_numpy(arr) != tensor[:, col]).any():
                fail(f"time {t}: {name} differs from stress component {col}")
        if not (abs(tensor[:, 0]).max() > 0.0):
            fail(f"time {t}: stress is zero everywhere")
    what = ("boundary and field blocks at every time, stress a named 6-component tensor"
            if with_field else "the boundary at every time (no interior field)")
    print(f"check_pvd_paraview: {pvd}: {len(times)} times from {times[0]:g} to {times[-1]:g}, "
          f"{what}: ok")
    check_states(run, times, with_field, with_thrust, with_mechanism)


main()
