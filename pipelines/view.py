"""Renders a run's final state off-screen in ParaView: the interior field warped by the
displacement and coloured by von Mises stress, with the boundary lines on top.

Usage: xvfb-run -a pvpython pipelines/view.py RUN_DIR OUT.png   (what `make view` runs)

The warp factor comes from the results: 5 % of the model size (the larger side of its
bounding box) over the largest displacement magnitude, rounded to 1, 2 or 5 times a power
of ten; it is printed and written in the picture's title.
"""
import math
import os
import sys

from paraview import servermanager
from paraview.simple import (ColorBy, GetActiveViewOrCreate, GetColorTransferFunction,
                             GetScalarBar, PVDReader, Render, ResetCamera, SaveScreenshot,
                             Show, Text, WarpByVector, ExtractBlock)  # noqa: F401
from vtkmodules.util.numpy_support import vtk_to_numpy


def nice(x):
    """x rounded to the nearest (on a log scale) of 1, 2 or 5 times a power of ten."""
    if not (x > 0 and math.isfinite(x)):
        return 1.0
    p = 10.0 ** math.floor(math.log10(x))
    return min((m * p for m in (1.0, 2.0, 5.0, 10.0)), key=lambda v: abs(math.log(v / x)))


def leaves(obj):
    if obj is None:
        return []
    if obj.IsA("vtkMultiBlockDataSet"):
        return [b for i in range(obj.GetNumberOfBlocks()) for b in leaves(obj.GetBlock(i))]
    return [obj]


def text_field(block, name):
    a = block.GetFieldData().GetArray(name)
    if a is None:
        return ""
    return bytes(int(a.GetValue(i)) for i in range(a.GetNumberOfTuples())).decode()


def main():
    run, png = sys.argv[1], sys.argv[2]
    reader = PVDReader(FileName=os.path.join(run, "vtk", "history.pvd"))
    reader.UpdatePipelineInformation()
    t = list(reader.TimestepValues)[-1]
    reader.UpdatePipeline(t)
    blocks = leaves(servermanager.Fetch(reader))
    field = [b for b in blocks if b.GetPointData().GetArray("stress") is not None]
    show = field[0] if field else blocks[0]
    pts = vtk_to_numpy(show.GetPoints().GetData())
    u = vtk_to_numpy(show.GetPointData().GetArray("displacement"))
    size = float((pts.max(axis=0) - pts.min(axis=0)).max())
    umax = float(abs(u).max() and (u ** 2).sum(axis=1).max() ** 0.5)
    factor = nice(0.05 * size / umax) if umax > 0 else 1.0
    print(f"view: {run}: model size {size:g}, max |u| {umax:.4g}, warp factor {factor:g}")

    view = GetActiveViewOrCreate("RenderView")
    view.ViewTime = t          # the final state (the view starts at the first time)
    view.ViewSize = [1600, 700]
    view.OrientationAxesVisibility = 0
    view.Background = [1.0, 1.0, 1.0]
    try:
        view.UseColorPaletteForBackground = 0
    except AttributeError:
        pass
    parts = []
    for index, colour in ((2, "von_mises"), (1, None)):
        # Block indices of the multiblock: 1 the boundary part, 2 the field part.
        if colour and not field:
            continue
        part = ExtractBlock(Input=reader)
        try:
            part.Selectors = ["/Root/Block1" if index == 2 else "/Root/Block0"]
        except AttributeError:
            part.BlockIndices = [index]
        warp = WarpByVector(Input=part)
        warp.Vectors = ["POINTS", "displacement"]
        warp.ScaleFactor = factor
        d = Show(warp, view)
        if colour:
            ColorBy(d, ("POINTS", colour))
            lut = GetColorTransferFunction(colour)
            lut.ApplyPreset("Viridis (matplotlib)", True)
            d.SetScalarBarVisibility(view, True)
            bar = GetScalarBar(lut, view)
            unit = text_field(show, "stress_unit")
            bar.Title = f"von Mises ({unit})" if unit else "von Mises"
            bar.ComponentTitle = ""
            bar.TitleColor = bar.LabelColor = [0, 0, 0]
        else:
            ColorBy(d, None)
            d.AmbientColor = d.DiffuseColor = [0.0, 0.0, 0.0]
            d.LineWidth = 2.0
        parts.append(warp)
    title = text_field(show, "title") or os.path.basename(run.rstrip("/"))
    label = Text(Text=f"{title}: final state, displacement x{factor:g}")
    ld = Show(label, view)
    ld.Color = [0, 0, 0]
    ld.FontSize = 14
    ld.WindowLocation = "Upper Center"
    # Fit the model's bounding box (with room for the warp) in the picture.
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    centre = 0.5 * (lo + hi)
    w, h = float(hi[0] - lo[0]), float(hi[1] - lo[1])
    view.CameraParallelProjection = 1
    view.CameraPosition = [centre[0], centre[1], 10 * size]
    view.CameraFocalPoint = [centre[0], centre[1], 0]
    view.CameraViewUp = [0, 1, 0]
    view.CameraParallelScale = 0.62 * max(h, w * 700 / 1600) + 0.05 * size
    Render(view)
    SaveScreenshot(png, view, ImageResolution=[1600, 700])
    print(f"view: {png}")


main()
