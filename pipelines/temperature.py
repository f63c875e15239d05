# script-version: 2
# spate in-situ pipeline: the water coloured by temperature, with a slice through it (heat transfer,
# a case with a `heat:` section).
#
# As free_surface.py, the fluid particles are interpolated with an SPH kernel (ParaView's SPH
# Volume Interpolator, Wendland kernel, spatial step dp) onto a grid over the tank, and the water is
# where the Shepard sum S = sum_j W_ij dp^d exceeds 0.5; its colour is the SPH estimate of the
# temperature, sum_j T_j W_ij dp^d / S. In 3D a slice through the water (a plane normal to y through
# the tank's middle unless SPATE_TEMPERATURE_SLICE says otherwise) shows the inside face on, with the
# free surface (the 0.5 contour) of the water beyond it; in 2D the water region is the slice.
# The solids are drawn as their particles, coloured by their own temperature (a heater, a liner:
# conjugate heat transfer shows across the interface), the tank's walls as grey points. The colour map
# (Inferno, dark = cold, bright = hot) and its scale bar, in kelvin, belong to this script alone.
# PNGs go to <run output>/insitu/temperature_<step>.png.
#
# Environment (scripts take no arguments):
#   SPATE_INSITU_IMAGE_SIZE=WxH        image size (default 1200x800)
#   SPATE_TEMPERATURE_RANGE=lo,hi      colour range [K] (default: the water's and the solids' range
#                                      at the first step, growing with the run's; never shrinking)
#   SPATE_TEMPERATURE_SLICE=axis,pos   3D: the slice's normal axis (x, y or z) and its position [m]
#                                      (default y through the middle of the tank)
#   SPATE_TEMPERATURE_DATA=1           also write the coloured water (2D) or the slice's water (3D)
#                                      with its values: insitu/temperature_<step>.vtu
# Case constants come from the dataset's field data (dp, dimensions, fluids), put there by spate.
import os

from paraview.simple import *
from paraview import catalyst

width, height = (int(v) for v in os.environ.get("SPATE_INSITU_IMAGE_SIZE", "1200x800").split("x"))
write_data = os.environ.get("SPATE_TEMPERATURE_DATA", "0") == "1"
fixed_range = os.environ.get("SPATE_TEMPERATURE_RANGE", "")
fixed_range = [float(v) for v in fixed_range.split(",")] if fixed_range else None
slice_at = os.environ.get("SPATE_TEMPERATURE_SLICE", "")

particles = TrivialProducer(registrationName="particles")

fluid = Threshold(registrationName="fluid", Input=particles)
fluid.Scalars = ["POINTS", "kind"]
fluid.LowerThreshold = 0
fluid.UpperThreshold = 0
fluid.ThresholdMethod = "Between"
fluid_all = MergeBlocks(registrationName="fluid_all", Input=fluid)

# The tank's walls (grey: behind a face with a condition they hold mirror values, not a
# temperature of their own) and the solids (coloured).
walls = Threshold(registrationName="walls", Input=particles)
walls.Scalars = ["POINTS", "kind"]
walls.LowerThreshold = 1
walls.UpperThreshold = 255
walls.ThresholdMethod = "Between"
tank = Threshold(registrationName="tank", Input=particles)
tank.Scalars = ["POINTS", "kind"]
tank.ThresholdMethod = "Between"
solids = Threshold(registrationName="solids", Input=particles)
solids.Scalars = ["POINTS", "kind"]
solids.UpperThreshold = 255
solids.ThresholdMethod = "Between"

view = CreateView("RenderView")
view.ViewSize = [width, height]
view.OrientationAxesVisibility = 0
view.UseColorPaletteForBackground = 0
view.BackgroundColorMode = "Gradient"
view.Background2 = [0.32, 0.34, 0.43]
view.Background = [0.85, 0.87, 0.9]

clock = Text(registrationName="clock")
clock_shown = Show(clock, view)
clock_shown.WindowLocation = "Upper Left Corner"
clock_shown.Color = [0.05, 0.05, 0.05]
clock_shown.FontSize = max(10, height // 40)

png = CreateExtractor("PNG", view, registrationName="temperature_png")
png.Trigger = "TimeStep"
png.Trigger.Frequency = 1
png.Writer.FileName = "temperature_{timestep:06d}.png"
png.Writer.ImageResolution = [width, height]

options = catalyst.Options()
options.ExtractsOutputDirectory = "insitu"
options.GlobalTrigger = "TimeStep"

_scene = None
_lut = None
_span = None
_time = 0.0


def _constant(name, fallback):
    data = particles.GetClientSideObject().GetOutputDataObject(0)
    array = data.GetFieldData().GetArray(name) if data else None
    return array.GetValue(0) if array else fallback


def _colour(shown, array):
    """Colours by `array` with this script's own colour map and one scale bar for all."""
    global _lut
    ColorBy(shown, ("POINTS", array), separate=True)
    if _lut is None:
        _lut = shown.LookupTable
        _lut.ApplyPreset("Inferno (matplotlib)", True)
        _lut.AutomaticRescaleRangeMode = "Never"  # catalyst_execute grows it
        _lut.RescaleTransferFunction(*_span)
        bar = GetScalarBar(_lut, view)
        bar.Title = "temperature [K]"
        bar.ComponentTitle = ""
        bar.AutomaticLabelFormat = 0
        bar.LabelFormat = "%-#.1f"
        bar.RangeLabelFormat = "%-#.1f"
        bar.WindowLocation = "Any Location"
        bar.Position = [0.82, 0.05]
        bar.ScalarBarLength = 0.33
        bar.TitleColor = bar.LabelColor = [0.05, 0.05, 0.05]
        shown.SetScalarBarVisibility(view, True)
    else:
        shown.LookupTable = _lut  # the walls and the slice share the water's map


def _grow_range():
    """The given range, or the water's and the solids' so far: it grows with the run's and never
    shrinks, so that a colour keeps its temperature from one image to the next once the extremes
    are reached (at least 1 K wide)."""
    global _span
    if fixed_range:
        _span = fixed_range
        return
    lo, hi = (_span[0], _span[1]) if _span else (float("inf"), float("-inf"))
    for source in (fluid_all, solids):
        source.UpdatePipeline(_time)  # this step's data (the render would update it only afterwards)
        info = source.GetDataInformation().GetPointDataInformation().GetArrayInformation("temperature")
        if info:
            r = info.GetComponentRange(0)
            lo, hi = min(lo, r[0]), max(hi, r[1])
    if hi - lo < 1.0:
        lo, hi = 0.5 * (lo + hi) - 0.5, 0.5 * (lo + hi) + 0.5
    _span = [lo, hi]
    if _lut is not None:
        _lut.RescaleTransferFunction(lo, hi)


def _normalised(interpolated, name="normalised"):
    """The interpolated temperature divided by the Shepard sum (0 where no particle is in reach)."""
    calc = Calculator(registrationName=name, Input=interpolated)
    calc.ResultArrayName = "temperature_normalised"
    calc.Function = "temperature/max(shepard,1e-6)"
    return calc


def _build_scene():
    """Once, from the first step's data: the grid, the wall particles and the camera."""
    dim = int(_constant("dimensions", 3))
    dp = _constant("dp", 0.01)
    fluids = int(_constant("fluids", 1))
    fluid.UpperThreshold = fluids - 1  # every fluid
    walls.LowerThreshold = fluids
    tank.LowerThreshold = tank.UpperThreshold = fluids
    solids.LowerThreshold = fluids + 1
    walls.UpdatePipeline()
    solids.UpdatePipeline()
    fluid_all.UpdatePipeline()
    if "temperature" not in fluid_all.PointData.keys():
        raise RuntimeError("temperature.py: the particles have no temperature (the case has no heat: section)")
    _grow_range()
    wb = walls.GetDataInformation().GetBounds()

    sph = SPHVolumeInterpolator(registrationName="sph", Input=fluid_all, Source="Bounded Volume")
    sph.Kernel = "SPHWendlandQuinticKernel"
    sph.Kernel.SpatialStep = dp
    sph.Kernel.Dimension = dim
    sph.ExcludedArrays = [a for a in fluid_all.PointData.keys() if a != "temperature"]
    sph.ComputeShepardSum = 1
    sph.ShepardSumArrayName = "shepard"
    box = sph.Source
    box.RefinementMode = "Use cell-size"
    box.CellSize = dp
    tank_shown = Show(tank, view)
    tank_shown.SetRepresentationType("Points")
    tank_shown.ColorArrayName = [None, ""]
    tank_shown.AmbientColor = tank_shown.DiffuseColor = [0.3, 0.3, 0.3]
    solids_shown = Show(solids, view)
    solids_shown.SetRepresentationType("Points")
    _colour(solids_shown, "temperature")

    if dim == 3:
        box.Origin = [wb[0], wb[2], wb[4]]
        box.Scale = [wb[1] - wb[0], wb[3] - wb[2], wb[5] - wb[4]]
        axis, position = "y", 0.5 * (wb[2] + wb[3])
        if slice_at:
            axis, position = slice_at.split(",")[0].strip(), float(slice_at.split(",")[1])
        normal = {"x": [1, 0, 0], "y": [0, 1, 0], "z": [0, 0, 1]}[axis]
        origin = [position if normal[k] else 0.5 * (wb[2 * k] + wb[2 * k + 1]) for k in range(3)]
        # The water beyond the slice (its surface, the 0.5 contour of the Shepard sum), cut open
        # where the slice is, so that the slice shows the inside face on.
        beyond = Clip(registrationName="beyond", Input=sph)
        beyond.ClipType = "Plane"
        beyond.ClipType.Origin = origin
        beyond.ClipType.Normal = normal
        beyond.Invert = 0
        surface = Contour(registrationName="surface", Input=beyond)
        surface.ContourBy = ["POINTS", "shepard"]
        surface.Isosurfaces = [0.5]
        surface.ComputeScalars = 1
        surface.ComputeNormals = 1
        _colour(Show(_normalised(surface, "surface_normalised"), view), "temperature_normalised")
        cut = Slice(registrationName="slice", Input=sph)
        cut.SliceType = "Plane"
        cut.SliceType.Origin = origin
        cut.SliceType.Normal = normal
        # The slice's water: where the Shepard sum is above 0.5 (a smooth edge, not the grid's cells).
        in_water = Clip(registrationName="in_water", Input=cut)
        in_water.ClipType = "Scalar"
        in_water.Scalars = ["POINTS", "shepard"]
        in_water.Value = 0.5
        in_water.Invert = 0
        water = _normalised(in_water, "slice_normalised")
        tank_shown.PointSize = solids_shown.PointSize = 1.0
        tank_shown.Opacity = 0.2
        # The three-quarter view of free_surface.py, from the side the slice faces.
        centre = [(wb[0] + wb[1]) / 2, (wb[2] + wb[3]) / 2, (wb[4] + wb[5]) / 2]
        size = max(wb[1] - wb[0], wb[3] - wb[2], wb[5] - wb[4])
        view.CameraFocalPoint = [centre[0], centre[1], wb[4] + 0.15 * (wb[5] - wb[4])]
        view.CameraPosition = [centre[0] + 0.55 * size, centre[1] - 1.05 * size, wb[4] + 0.85 * size]
        view.CameraViewUp = [0, 0, 1]
        view.CameraViewAngle = 30
        view.ResetCamera([wb[0], wb[1], wb[2], wb[3], wb[4], wb[5]], 0.8)
    else:
        box.Origin = [wb[0], wb[2], -0.5 * dp]
        box.Scale = [wb[1] - wb[0], wb[3] - wb[2], dp]
        water = Threshold(registrationName="water", Input=_normalised(sph))
        water.Scalars = ["POINTS", "shepard"]
        water.LowerThreshold = 0.5
        water.UpperThreshold = 1.0e30
        water.ThresholdMethod = "Between"
        water.AllScalars = 0
        tank_shown.PointSize = solids_shown.PointSize = 3.0
        view.InteractionMode = "2D"
        view.CameraParallelProjection = 1
        view.CameraPosition = [(wb[0] + wb[1]) / 2, (wb[2] + wb[3]) / 2, 1.0]
        view.CameraFocalPoint = [(wb[0] + wb[1]) / 2, (wb[2] + wb[3]) / 2, 0.0]
        view.CameraViewUp = [0, 1, 0]
        view.ResetCamera([wb[0], wb[1], wb[2], wb[3], -0.01, 0.01], 0.95)
    water_shown = Show(water, view)
    water_shown.Ambient, water_shown.Diffuse = 1.0, 0.0  # the slice's true colours, unshaded
    _colour(water_shown, "temperature_normalised")
    if write_data:
        data = CreateExtractor("VTU", water, registrationName="temperature_data")
        data.Trigger = "TimeStep"
        data.Trigger.Frequency = 1
        data.Writer.FileName = "temperature_{timestep:06d}.vtu"
    return sph


def catalyst_execute(info):
    global _scene, _time
    _time = info.time
    particles.UpdatePipeline(info.time)
    clock.Text = "t = %.3f s   (step %d)" % (info.time, info.timestep)
    if _scene is None:
        _scene = _build_scene()
    _grow_range()
