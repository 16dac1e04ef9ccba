"""Renders a run's final state off-screen in ParaView: the interior field (where the run
computed one) warped by the displacement and coloured by von Mises stress, with the boundary
lines on top (black over a field, else coloured by contact status), and the thrust line
(where the run has interfaces: the joints' points of application, in blue), and where the
run failed at a mechanism or its collapse search found one, the mechanism (the boundary
lines of the moving bodies warped by `mechanism_velocity`, the fastest node by 10 % of the
model size, in orange: where they go); saves the same view as a ParaView state file for the GUI.

Contact status as named categories: the colour maps of `contact_status` (-1 not an
interface, 0 open, 1 closed) and `tangential_status` (-1 no friction, 0 open, 1 stick,
2 slip) are set to categories with these names (ParaView's annotations), in the picture and
in the saved state, so that colouring by them in the GUI shows a legend of names. (The
files keep integers: a string array would make meshio refuse the whole file.)

Usage: xvfb-run -a pvpython pipelines/view.py RUN_DIR OUT.png   (what `make view` runs)

Reads RUN_DIR/vtk/states.pvd (one multiblock per time, blocks "boundary", where computed
"field", where the run has interfaces "thrust" and "contact", at the last time where it
has one "mechanism"), or history.pvd of older runs; either may come back from ParaView's
reader as a multiblock or, with a single part, as a plain grid: both are handled. The view
is set at the last time step. The warp factor comes from the results: 5 % of the model size
(the larger side of its bounding box) over the largest displacement magnitude, rounded to
1, 2 or 5 times a power of ten; it is printed and written in the picture's title. The blocks
at that time are printed by name ("view: RUN: blocks at time T: boundary field ..."). Writes
RUN_DIR/vtk/view.pvsm (File > Load State in ParaView opens this view at the last time).
"""
import math
import os
import sys

from paraview import servermanager
from paraview.simple import (Calculator, ColorBy, ExtractBlock, GetActiveViewOrCreate,
                             GetAnimationScene, GetColorTransferFunction, GetScalarBar,
                             PVDReader, Render, SaveScreenshot, SaveState, Show, Text,
                             Threshold, WarpByVector)
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonDataModel import vtkCompositeDataSet


def nice(x):
    """x rounded to the nearest (on a log scale) of 1, 2 or 5 times a power of ten."""
    if not (x > 0 and math.isfinite(x)):
        return 1.0
    p = 10.0 ** math.floor(math.log10(x))
    return min((m * p for m in (1.0, 2.0, 5.0, 10.0)), key=lambda v: abs(math.log(v / x)))


def leaves(obj, path=("Root",)):
    """(selector path, dataset) of every leaf; the path as ParaView's ExtractBlock selectors
    name it: a block's name, or Block<index> for an unnamed one. A plain grid is one leaf
    with no path."""
    if obj is None:
        return []
    if not obj.IsA("vtkMultiBlockDataSet"):
        return [(None if len(path) == 1 else "/" + "/".join(path), obj)]
    out = []
    for i in range(obj.GetNumberOfBlocks()):
        meta = obj.GetMetaData(i) if obj.HasMetaData(i) else None
        name = meta.Get(vtkCompositeDataSet.NAME()) if meta is not None and \
            meta.Has(vtkCompositeDataSet.NAME()) else f"Block{i}"
        out.extend(leaves(obj.GetBlock(i), path + (name,)))
    return out


def text_field(block, name):
    a = block.GetFieldData().GetArray(name)
    if a is None:
        return ""
    return bytes(int(a.GetValue(i)) for i in range(a.GetNumberOfTuples())).decode()


def open_series(run):
    """The run's series (states.pvd, else history.pvd) at its last time: (reader, time)."""
    vtk = os.path.join(os.path.abspath(run), "vtk")
    for name in ("states.pvd", "history.pvd"):
        path = os.path.join(vtk, name)
        if os.path.exists(path):
            break
    else:
        sys.exit(f"view: {run}: no vtk/states.pvd nor vtk/history.pvd (output.vtk = false?)")
    reader = PVDReader(FileName=path)
    reader.UpdatePipelineInformation()
    times = list(reader.TimestepValues) or [0.0]
    t = times[-1]
    scene = GetAnimationScene()
    scene.UpdateAnimationUsingDataTimeSteps()
    scene.AnimationTime = t    # the GUI and the saved state open at the final state
    reader.UpdatePipeline(t)
    return reader, t


def part(reader, selector):
    """The block at `selector` of the reader's output, or the whole output (a plain grid)."""
    if selector is None:
        return reader
    block = ExtractBlock(Input=reader)
    block.Selectors = [selector]
    return block


# Named categories of the integer status arrays: (value, name, RGB).
CATEGORIES = {
    "contact_status": [(-1, "not an interface", (0.0, 0.0, 0.0)),
                       (0, "open", (0.89, 0.10, 0.11)),
                       (1, "closed", (0.13, 0.55, 0.13))],
    "tangential_status": [(-1, "no friction", (0.0, 0.0, 0.0)),
                          (0, "open", (0.89, 0.10, 0.11)),
                          (1, "stick", (0.13, 0.55, 0.13)),
                          (2, "slip", (0.12, 0.47, 0.71))],
}


def categories(name):
    """The colour map of status array `name` as named categories (ParaView annotations)."""
    lut = GetColorTransferFunction(name)
    lut.InterpretValuesAsCategories = 1
    lut.Annotations = [str(v) for c in CATEGORIES[name] for v in (c[0], c[1])]
    lut.IndexedColors = [x for c in CATEGORIES[name] for x in c[2]]
    return lut


def show_part(source, view, factor, colour, unit):
    warp = WarpByVector(Input=source)
    warp.Vectors = ["POINTS", "displacement"]
    warp.ScaleFactor = factor
    d = Show(warp, view)
    if colour in CATEGORIES:
        ColorBy(d, ("POINTS", colour))
        bar = GetScalarBar(categories(colour), view)
        d.SetScalarBarVisibility(view, True)
        bar.Title = colour.replace("_", " ")
        bar.ComponentTitle = ""
        bar.TitleColor = bar.LabelColor = [0, 0, 0]
        d.LineWidth = 2.0
    elif colour:
        ColorBy(d, ("POINTS", colour))
        lut = GetColorTransferFunction(colour)
        lut.ApplyPreset("Viridis (matplotlib)", True)
        d.SetScalarBarVisibility(view, True)
        bar = GetScalarBar(lut, view)
        bar.Title = f"von Mises ({unit})" if unit else "von Mises"
        bar.ComponentTitle = ""
        bar.TitleColor = bar.LabelColor = [0, 0, 0]
    else:
        ColorBy(d, None)
        d.AmbientColor = d.DiffuseColor = [0.0, 0.0, 0.0]
        d.LineWidth = 2.0
    return warp


def main():
    run, png = sys.argv[1], sys.argv[2]
    reader, t = open_series(run)
    blocks = leaves(servermanager.Fetch(reader))
    thrust = [(s, b) for s, b in blocks if s is not None and s.endswith("/thrust")]
    # The contact rows' points are for colouring by their own arrays in the GUI, not drawn.
    contact = [(s, b) for s, b in blocks if s is not None and s.endswith("/contact")]
    mechanism = [(s, b) for s, b in blocks if s is not None and s.endswith("/mechanism")]
    field = [(s, b) for s, b in blocks if b.GetPointData().GetArray("stress") is not None]
    boundary = [(s, b) for s, b in blocks
                if b.GetPointData().GetArray("stress") is None and (s, b) not in thrust
                and (s, b) not in contact and (s, b) not in mechanism]
    # Every block at this time by name (an unnamed block as its index, a plain grid as
    # "grid"): what a test checks against the run.
    names = [s.rsplit("/", 1)[-1] if s is not None else "grid" for s, _ in blocks]
    print(f"view: {run}: blocks at time {t:g}: {' '.join(names)}")
    if not boundary:
        sys.exit(f"view: {run}: the series has no boundary block at time {t:g}")
    show = field[0][1] if field else boundary[0][1]
    pts = vtk_to_numpy(show.GetPoints().GetData())
    u = vtk_to_numpy(show.GetPointData().GetArray("displacement"))
    size = float((pts.max(axis=0) - pts.min(axis=0)).max())
    umax = float(abs(u).max() and (u ** 2).sum(axis=1).max() ** 0.5)
    factor = nice(0.05 * size / umax) if umax > 0 else 1.0
    print(f"view: {run}: model size {size:g}, max |u| {umax:.4g}, warp factor {factor:g}, "
          f"time {t:g}, blocks: {'boundary and field' if field else 'boundary only'}"
          f"{', thrust line' if thrust else ''}{', mechanism' if mechanism else ''}")

    view = GetActiveViewOrCreate("RenderView")
    view.ViewTime = t
    view.ViewSize = [1600, 700]
    view.OrientationAxesVisibility = 0
    view.Background = [1.0, 1.0, 1.0]
    try:
        view.UseColorPaletteForBackground = 0
    except AttributeError:
        pass
    unit = text_field(show, "stress_unit")
    for name in CATEGORIES:
        categories(name)    # named categories in the saved state too
    if field:
        show_part(part(reader, field[0][0]), view, factor, "von_mises", unit)
    show_part(part(reader, boundary[0][0]), view, factor,
              None if field else "contact_status", unit)
    if thrust:
        d = Show(WarpByVector(Input=part(reader, thrust[0][0]), Vectors=["POINTS", "displacement"],
                              ScaleFactor=factor), view)
        ColorBy(d, None)
        d.AmbientColor = d.DiffuseColor = [0.0, 0.3, 0.85]
        d.LineWidth = 3.0
        d.PointSize = 9.0
        d.RenderPointsAsSpheres = 1
    if mechanism:
        # The moving bodies' lines (every point with a velocity), warped so that the fastest
        # node of the mechanism (at 1) moves by 10 % of the model size.
        speed = Calculator(Input=part(reader, mechanism[0][0]), ResultArrayName="speed",
                           Function="mag(mechanism_velocity)")
        moving = Threshold(Input=speed, Scalars=["POINTS", "speed"], LowerThreshold=1e-9,
                           UpperThreshold=1e300, ThresholdMethod="Between", AllScalars=1)
        d = Show(WarpByVector(Input=moving, Vectors=["POINTS", "mechanism_velocity"],
                              ScaleFactor=0.1 * size), view)
        ColorBy(d, None)
        d.AmbientColor = d.DiffuseColor = [1.0, 0.5, 0.0]
        d.LineWidth = 2.0
    title = text_field(show, "title") or os.path.basename(run.rstrip("/"))
    label = Text(Text=f"{title}: final state, displacement x{factor:g}")
    ld = Show(label, view)
    ld.Color = [0, 0, 0]
    ld.FontSize = 14
    ld.WindowLocation = "Upper Center"
    # Fit the model's bounding box (with room for the warp) in the picture. The first
    # Render of paraview.simple resets the camera to the data's bounding sphere (a tight
    # framing, the title over the model's top): render once before the camera is set.
    Render(view)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    if mechanism:
        # The mechanism's lines move by up to 10 % of the model size (wall_collapse's right
        # end, turning, rose into the title's band).
        lo, hi = lo - 0.1 * size, hi + 0.1 * size
    centre = 0.5 * (lo + hi)
    w, h = float(hi[0] - lo[0]), float(hi[1] - lo[1])
    view.CameraParallelProjection = 1
    view.CameraPosition = [centre[0], centre[1], 10 * size]
    view.CameraFocalPoint = [centre[0], centre[1], 0]
    view.CameraViewUp = [0, 1, 0]
    view.CameraParallelScale = 0.62 * max(h, w * 700 / 1600) + 0.05 * size
    Render(view)
    SaveScreenshot(png, view, ImageResolution=[1600, 700])
    state = os.path.join(run, "vtk", "view.pvsm")
    SaveState(state)
    print(f"view: {png}; ParaView state {state}")


main()
