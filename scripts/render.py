#!/usr/bin/python3
"""Render a phymul result (.vtu, or the last frame of a .pvd) to a PNG picture.

usage: render.py INPUT OUTPUT.png [--field NAME] [--title TEXT] [--rest]
                 [--view iso|front|side|top]

The surface of the mesh is coloured by the magnitude of a point field (default
"displacement"; plain colour when the file has none). Lengths are stored in metres and
shown in millimetres. --rest also draws the undeformed shape (points - displacement) as a
grey wireframe. Rendering is off-screen; run under `xvfb-run -a` where there is no display.

Exit status: 0 on success, 2 for bad arguments, a missing/unreadable input or an unknown
field, 1 when rendering itself fails.
"""

import argparse
import math
import os
import re
import sys
import xml.etree.ElementTree as ET

DEFAULT_FIELD = "displacement"
BACKGROUND = (1.0, 1.0, 1.0)
TEXT_COLOUR = (0.0, 0.0, 0.0)
PLAIN_COLOUR = (0.85, 0.55, 0.45)
REST_COLOUR = (0.72, 0.72, 0.72)
OBSTACLE_COLOUR = (0.55, 0.58, 0.62)
SIZE = (1200, 900)

# Viridis, sampled: perceptually uniform and readable in grey scale, unlike a rainbow.
VIRIDIS = [
    (0.000, (0.267, 0.005, 0.329)),
    (0.125, (0.283, 0.141, 0.458)),
    (0.250, (0.254, 0.265, 0.530)),
    (0.375, (0.207, 0.372, 0.553)),
    (0.500, (0.164, 0.471, 0.558)),
    (0.625, (0.128, 0.567, 0.551)),
    (0.750, (0.135, 0.659, 0.518)),
    (0.875, (0.478, 0.821, 0.318)),
    (1.000, (0.993, 0.906, 0.144)),
]


class UsageError(Exception):
    """Bad input from the user: reported on one line, exit status 2."""


def parse_args(argv):
    parser = argparse.ArgumentParser(
        prog="render.py",
        description="Render a phymul .vtu/.pvd result to PNG (off-screen).")
    parser.add_argument("input", help=".vtu file, or .pvd collection (its last frame is used)")
    parser.add_argument("output", help="PNG file to write")
    parser.add_argument("--field", default=None,
                        help=f"point field to colour by (default: {DEFAULT_FIELD}, if present)")
    parser.add_argument("--title", default=None, help="title text (default: the file name)")
    parser.add_argument("--rest", action="store_true",
                        help="also draw the undeformed shape as a grey wireframe")
    parser.add_argument("--view", choices=["iso", "below", "front", "side", "top"],
                        default="iso",
                        help="camera direction (default: iso, from above; below: from under)")
    return parser.parse_args(argv)


def last_frame(pvd_path):
    """(vtu path, time) of the frame with the largest time step in a .pvd collection."""
    try:
        root = ET.parse(pvd_path).getroot()
    except (ET.ParseError, OSError) as error:
        raise UsageError(f"cannot read {pvd_path}: {error}") from error
    frames = []
    for index, dataset in enumerate(root.iter("DataSet")):
        name = dataset.get("file")
        if not name:
            continue
        try:
            time = float(dataset.get("timestep", "nan"))
        except ValueError:
            time = math.nan
        frames.append((time if math.isfinite(time) else -math.inf, index, name))
    if not frames:
        raise UsageError(f"{pvd_path} lists no DataSet with a file")
    time, _, name = max(frames)
    # Frame names are relative to the collection, not to the working directory.
    path = os.path.join(os.path.dirname(os.path.abspath(pvd_path)), name)
    return path, (time if math.isfinite(time) else None)


def obstacle_grid(vtu_path, kind="obstacles"):
    """The obstacles' surfaces (or, kind "needles", the needles' shafts, track points and
    targets) written with a frame (<stem>_<kind>_<n>.vtu), or None."""
    match = re.match(r"^(.*)_(\d+)\.vtu$", os.path.basename(vtu_path))
    if not match:
        return None
    path = os.path.join(os.path.dirname(vtu_path),
                        f"{match.group(1)}_{kind}_{match.group(2)}.vtu")
    return read_grid(path) if os.path.isfile(path) else None


def read_grid(path):
    from vtkmodules.vtkCommonCore import vtkCommand
    from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader

    if not os.path.isfile(path):
        raise UsageError(f"no such file: {path}")
    errors = []
    reader = vtkXMLUnstructuredGridReader()
    # VTK reports parse errors through events, not exceptions; collect them to fail clearly.
    reader.AddObserver(vtkCommand.ErrorEvent, lambda obj, event: errors.append(event))
    reader.GetExecutive().AddObserver(vtkCommand.ErrorEvent,
                                      lambda obj, event: errors.append(event))
    reader.SetFileName(path)
    reader.Update()
    grid = reader.GetOutput()
    if errors or reader.GetErrorCode() != 0 or grid is None or grid.GetNumberOfPoints() == 0:
        raise UsageError(f"cannot read {path} as a VTK unstructured grid (.vtu) with points")
    return grid


def point_field_names(grid):
    data = grid.GetPointData()
    return [data.GetArrayName(i) for i in range(data.GetNumberOfArrays())]


def numpy_of(array):
    from vtkmodules.util.numpy_support import vtk_to_numpy

    values = vtk_to_numpy(array)
    return values.reshape(len(values), -1)


def add_colour_array(grid, field):
    """Adds the array to colour by; returns (array name, label, unit, (lo, hi), peak)."""
    import numpy as np
    from vtkmodules.util.numpy_support import numpy_to_vtk

    values = numpy_of(grid.GetPointData().GetArray(field))
    components = values.shape[1]
    # Vectors are shown as magnitudes; lengths (displacement, ...) are metres in the files
    # and millimetres read better for soft tissue.
    is_length = components == 3 and "displacement" in field.lower()
    shown = np.linalg.norm(values, axis=1) if components > 1 else values[:, 0].copy()
    if is_length:
        shown *= 1000.0
    label = f"|{field}|" if components > 1 else field
    unit = "mm" if is_length else ""
    lo, hi = float(np.min(shown)), float(np.max(shown))
    if components > 1:
        lo = 0.0  # a magnitude scale reads best from zero
    if not hi > lo:
        hi = lo + (abs(lo) * 1e-6 if lo != 0.0 else 1.0)
    array = numpy_to_vtk(np.ascontiguousarray(shown, dtype=np.float64), deep=1)
    array.SetName("__render_colour")
    grid.GetPointData().AddArray(array)
    return "__render_colour", label, unit, (lo, hi), float(np.max(shown))


def surface_of(grid):
    from vtkmodules.vtkFiltersGeometry import vtkDataSetSurfaceFilter

    surface = vtkDataSetSurfaceFilter()
    surface.SetInputData(grid)
    surface.Update()
    return surface.GetOutput()


def rest_grid(grid, field):
    import numpy as np
    from vtkmodules.util.numpy_support import numpy_to_vtk
    from vtkmodules.vtkCommonCore import vtkPoints
    from vtkmodules.vtkCommonDataModel import vtkUnstructuredGrid

    points = numpy_of(grid.GetPoints().GetData())
    displacement = numpy_of(grid.GetPointData().GetArray(field))
    rest = vtkUnstructuredGrid()
    rest.CopyStructure(grid)
    rest_points = vtkPoints()
    rest_points.SetData(numpy_to_vtk(np.ascontiguousarray(points - displacement), deep=1))
    rest.SetPoints(rest_points)
    return rest


def lookup_table(lo, hi):
    from vtkmodules.vtkRenderingCore import vtkColorTransferFunction
    from vtkmodules.vtkCommonCore import vtkLookupTable

    ctf = vtkColorTransferFunction()
    for x, (r, g, b) in VIRIDIS:
        ctf.AddRGBPoint(x, r, g, b)
    table = vtkLookupTable()
    table.SetNumberOfTableValues(256)
    for i in range(256):
        r, g, b = ctf.GetColor(i / 255.0)
        table.SetTableValue(i, r, g, b, 1.0)
    table.SetRange(lo, hi)
    table.Build()
    return table


def text_property(prop, size, bold=False):
    prop.SetColor(*TEXT_COLOUR)
    prop.SetFontSize(size)
    prop.SetBold(bold)
    prop.SetItalic(False)
    prop.SetShadow(False)
    prop.SetFontFamilyToArial()


def set_camera(renderer, view, bounds, leave_room_right):
    camera = renderer.GetActiveCamera()
    centre = [(bounds[0] + bounds[1]) / 2, (bounds[2] + bounds[3]) / 2,
              (bounds[4] + bounds[5]) / 2]
    # z is up (gravity along -z); directions point from the focal point to the eye.
    direction, up = {
        "iso": ((1.0, -1.0, 0.8), (0.0, 0.0, 1.0)),
        "below": ((1.0, -1.0, -0.8), (0.0, 0.0, 1.0)),
        "front": ((0.0, -1.0, 0.0), (0.0, 0.0, 1.0)),
        "side": ((1.0, 0.0, 0.0), (0.0, 0.0, 1.0)),
        "top": ((0.0, 0.0, 1.0), (0.0, 1.0, 0.0)),
    }[view]
    camera.SetFocalPoint(*centre)
    camera.SetPosition(*(c + d for c, d in zip(centre, direction)))
    camera.SetViewUp(*up)
    perspective = view in ("iso", "below")
    camera.SetParallelProjection(not perspective)
    # Framed on the body: an obstacle (a plane, a probe's shaft) may reach far beyond it.
    renderer.ResetCamera(bounds)
    camera.Zoom(0.85 if perspective else 0.9)
    if leave_room_right:
        # Moves the model left so that the colour bar on the right does not cover it.
        camera.SetWindowCenter(0.12, 0.0)
    renderer.ResetCameraClippingRange()


def render(args):
    # Imported here so that --help and argument errors do not pay for loading VTK.
    import vtkmodules.vtkInteractionStyle  # noqa: F401  (registers the default style)
    import vtkmodules.vtkRenderingFreeType  # noqa: F401  (text rendering backend)
    import vtkmodules.vtkRenderingOpenGL2  # noqa: F401  (rendering backend)
    from vtkmodules.vtkIOImage import vtkPNGWriter
    from vtkmodules.vtkRenderingAnnotation import vtkScalarBarActor
    from vtkmodules.vtkRenderingCore import (vtkActor, vtkDataSetMapper, vtkRenderer,
                                             vtkRenderWindow, vtkTextActor,
                                             vtkWindowToImageFilter)

    if not os.path.exists(args.input):
        raise UsageError(f"no such file: {args.input}")
    time = None
    if args.input.lower().endswith(".pvd"):
        vtu_path, time = last_frame(args.input)
    else:
        vtu_path = args.input
    out_dir = os.path.dirname(os.path.abspath(args.output))
    if not os.path.isdir(out_dir):
        raise UsageError(f"output directory does not exist: {out_dir}")

    grid = read_grid(vtu_path)
    names = point_field_names(grid)
    field = args.field if args.field is not None else DEFAULT_FIELD
    if field not in names:
        if args.field is not None:
            available = ", ".join(names) if names else "none"
            raise UsageError(f"{vtu_path} has no point field '{field}' "
                             f"(point fields available: {available})")
        field = None

    rest_field = None
    if args.rest:
        # The undeformed shape needs a 3-component displacement to subtract.
        for candidate in ([field] if field else []) + [DEFAULT_FIELD]:
            if (candidate in names
                    and grid.GetPointData().GetArray(candidate).GetNumberOfComponents() == 3):
                rest_field = candidate
                break
        if rest_field is None:
            raise UsageError(f"--rest needs a 3-component point field '{DEFAULT_FIELD}' in "
                             f"{vtu_path} (point fields available: {', '.join(names) or 'none'})")

    colour = add_colour_array(grid, field) if field else None
    surface = surface_of(grid)

    renderer = vtkRenderer()
    renderer.SetBackground(*BACKGROUND)

    mapper = vtkDataSetMapper()
    mapper.SetInputData(surface)
    actor = vtkActor()
    actor.SetMapper(mapper)
    prop = actor.GetProperty()
    prop.EdgeVisibilityOn()
    prop.SetEdgeColor(0.15, 0.15, 0.15)
    prop.SetLineWidth(1.0)
    # Some ambient light keeps faces seen at grazing angles from turning black.
    prop.SetAmbient(0.25)
    prop.SetDiffuse(0.8)
    if colour:
        name, label, unit, (lo, hi), peak = colour
        bar_title = f"{label} ({unit})" if unit else label
        table = lookup_table(lo, hi)
        mapper.SetLookupTable(table)
        mapper.SetScalarModeToUsePointFieldData()
        mapper.SelectColorArray(name)
        mapper.SetScalarRange(lo, hi)
        mapper.ScalarVisibilityOn()
        mapper.SetInterpolateScalarsBeforeMapping(True)
    else:
        mapper.ScalarVisibilityOff()
        prop.SetColor(*PLAIN_COLOUR)
    renderer.AddActor(actor)
    # Needles run inside the body: it is drawn see-through, and they in red on top.
    needles = obstacle_grid(vtu_path, "needles")
    if needles is not None:
        prop.SetOpacity(0.5)
        needle_mapper = vtkDataSetMapper()
        needle_mapper.SetInputData(needles)
        needle_mapper.ScalarVisibilityOff()
        needle_actor = vtkActor()
        needle_actor.SetMapper(needle_mapper)
        needle_prop = needle_actor.GetProperty()
        needle_prop.SetColor(0.8, 0.1, 0.1)
        needle_prop.SetLineWidth(4.0)
        needle_prop.SetPointSize(9.0)
        needle_prop.LightingOff()
        renderer.AddActor(needle_actor)

    if rest_field:
        rest_mapper = vtkDataSetMapper()
        rest_mapper.SetInputData(surface_of(rest_grid(grid, rest_field)))
        rest_mapper.ScalarVisibilityOff()
        rest_actor = vtkActor()
        rest_actor.SetMapper(rest_mapper)
        rest_prop = rest_actor.GetProperty()
        rest_prop.SetRepresentationToWireframe()
        rest_prop.SetColor(*REST_COLOUR)
        rest_prop.SetLineWidth(1.0)
        rest_prop.LightingOff()
        renderer.AddActor(rest_actor)

    obstacles = obstacle_grid(vtu_path)
    if obstacles is not None:
        obstacle_mapper = vtkDataSetMapper()
        obstacle_mapper.SetInputData(obstacles)
        obstacle_mapper.ScalarVisibilityOff()
        obstacle_actor = vtkActor()
        obstacle_actor.SetMapper(obstacle_mapper)
        obstacle_prop = obstacle_actor.GetProperty()
        obstacle_prop.SetColor(*OBSTACLE_COLOUR)
        obstacle_prop.SetOpacity(0.45)
        obstacle_prop.SetAmbient(0.3)
        renderer.AddActor(obstacle_actor)

    if colour:
        bar = vtkScalarBarActor()
        bar.SetLookupTable(table)
        bar.SetTitle(bar_title)
        bar.SetNumberOfLabels(6)
        bar.SetLabelFormat("%.3g")
        bar.SetMaximumWidthInPixels(140)
        bar.SetMaximumHeightInPixels(560)
        bar.GetPositionCoordinate().SetCoordinateSystemToNormalizedViewport()
        bar.GetPositionCoordinate().SetValue(0.80, 0.18)
        bar.SetWidth(0.14)
        bar.SetHeight(0.64)
        bar.UnconstrainedFontSizeOn()
        bar.SetTextPad(6)
        bar.SetVerticalTitleSeparation(10)
        text_property(bar.GetTitleTextProperty(), 22, bold=True)
        text_property(bar.GetLabelTextProperty(), 18)
        renderer.AddActor2D(bar)

    title = args.title
    if title is None:
        title = os.path.basename(args.input)
    title_actor = vtkTextActor()
    title_actor.SetInput(title)
    text_property(title_actor.GetTextProperty(), 30, bold=True)
    title_actor.GetTextProperty().SetJustificationToCentered()
    title_actor.GetTextProperty().SetVerticalJustificationToTop()
    title_actor.GetPositionCoordinate().SetCoordinateSystemToNormalizedViewport()
    title_actor.GetPositionCoordinate().SetValue(0.5, 0.96)
    renderer.AddActor2D(title_actor)

    notes = []
    if time is not None:
        notes.append(f"t = {time:.6g} s")
    if colour:
        notes.append(f"max {label} = {peak:.4g} {unit}".rstrip())
    if rest_field:
        notes.append("grey wireframe: rest shape")
    if obstacles is not None:
        notes.append("translucent grey: rigid obstacles")
    if needles is not None:
        notes.append("red: needle shaft, track points and target")
    notes.append(f"{grid.GetNumberOfPoints()} nodes, {grid.GetNumberOfCells()} cells")
    notes_actor = vtkTextActor()
    notes_actor.SetInput("\n".join(notes))
    text_property(notes_actor.GetTextProperty(), 18)
    notes_actor.GetPositionCoordinate().SetCoordinateSystemToNormalizedViewport()
    notes_actor.GetPositionCoordinate().SetValue(0.02, 0.03)
    renderer.AddActor2D(notes_actor)

    bounds = list(surface.GetBounds())
    set_camera(renderer, args.view, bounds, leave_room_right=colour is not None)

    window = vtkRenderWindow()
    window.SetOffScreenRendering(1)
    window.SetSize(*SIZE)
    window.AddRenderer(renderer)
    window.Render()

    grab = vtkWindowToImageFilter()
    grab.SetInput(window)
    grab.SetInputBufferTypeToRGB()
    grab.ReadFrontBufferOff()
    grab.Update()
    writer = vtkPNGWriter()
    writer.SetFileName(args.output)
    writer.SetInputConnection(grab.GetOutputPort())
    writer.Write()
    if writer.GetErrorCode() != 0 or not os.path.isfile(args.output):
        raise RuntimeError(f"cannot write {args.output}")
    window.Finalize()


def main(argv=None):
    args = parse_args(sys.argv[1:] if argv is None else argv)
    try:
        render(args)
    except UsageError as error:
        print(f"render.py: {error}", file=sys.stderr)
        return 2
    except ImportError as error:
        print(f"render.py: {error}; install the Debian package python3-vtk9 "
              "(make deps-demo) and run with /usr/bin/python3", file=sys.stderr)
        return 1
    except Exception as error:  # noqa: BLE001  (one clear line instead of a traceback)
        print(f"render.py: rendering {args.input} failed: {error}", file=sys.stderr)
        return 1
    print(f"render.py: wrote {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
