# script-version: 2
# spate in-situ pipeline: the free surface, reconstructed from the particles and rendered off screen.
#
# The fluid particles are interpolated with an SPH kernel onto a regular grid that covers the tank
# (ParaView's SPH Volume Interpolator, Wendland kernel, spatial step dp so that the Shepard sum
# sum_j W_ij dp^d is 1 inside the water and 0 outside); the surface is the Shepard sum's 0.5
# contour, coloured by the interpolated speed. The tank floor, its outline and every solid (the
# column) are drawn too, from a three-quarter view like the paper's Figure 4. In 2D the water is
# the region where the Shepard sum exceeds 0.5, seen from the front.
# PNGs go to <run output>/insitu/free_surface_<step>.png.
#
# Environment: SPATE_INSITU_IMAGE_SIZE=WxH (default 1200x800); SPATE_FREE_SURFACE_CELL=c, grid cell
# size in units of dp (default 1; larger is faster: cost ~ 25 us per grid point on 2 cores);
# SPATE_FREE_SURFACE_PHASE=k, with several fluids the surface of fluid k (default 0, the first).
# Case constants come from the dataset's field data (dp, dimensions), put there by spate.
import os

from paraview.simple import *
from paraview import catalyst

width, height = (int(v) for v in os.environ.get("SPATE_INSITU_IMAGE_SIZE", "1200x800").split("x"))
cell_factor = float(os.environ.get("SPATE_FREE_SURFACE_CELL", "1.0"))

particles = TrivialProducer(registrationName="particles")

fluid = Threshold(registrationName="fluid", Input=particles)
fluid.Scalars = ["POINTS", "kind"]
fluid.LowerThreshold = 0
fluid.UpperThreshold = 0
fluid.ThresholdMethod = "Between"
# One interpolation over all devices' particles (the interpolator works on one dataset).
fluid_all = MergeBlocks(registrationName="fluid_all", Input=fluid)

walls = Threshold(registrationName="walls", Input=particles)
walls.Scalars = ["POINTS", "kind"]
walls.LowerThreshold = 1
walls.UpperThreshold = 255
walls.ThresholdMethod = "Between"

view = CreateView("RenderView")
view.ViewSize = [width, height]
view.OrientationAxesVisibility = 0
view.UseColorPaletteForBackground = 0
view.BackgroundColorMode = "Gradient"
view.Background2 = [0.32, 0.34, 0.43]
view.Background = [0.85, 0.87, 0.9]

speed = GetColorTransferFunction("velocity")
speed.ApplyPreset("Jet", True)
bar = GetScalarBar(speed, view)
bar.Title = "speed [m/s]"
bar.ComponentTitle = ""
bar.WindowLocation = "Any Location"
bar.Position = [0.89, 0.05]
bar.ScalarBarLength = 0.33

png = CreateExtractor("PNG", view, registrationName="free_surface_png")
png.Trigger = "TimeStep"
png.Trigger.Frequency = 1
png.Writer.FileName = "free_surface_{timestep:06d}.png"
png.Writer.ImageResolution = [width, height]

options = catalyst.Options()
options.ExtractsOutputDirectory = "insitu"
options.GlobalTrigger = "TimeStep"

_scene = None


def _constant(name, fallback):
    data = particles.GetClientSideObject().GetOutputDataObject(0)
    array = data.GetFieldData().GetArray(name) if data else None
    return array.GetValue(0) if array else fallback


def _fix_speed_range():
    # After ColorBy, which rescales to the data: a fixed range keeps images comparable over time.
    speed.AutomaticRescaleRangeMode = "Never"
    speed.RescaleTransferFunction(0.0, 3.0)


def _build_scene():
    """Once, from the first step's data: the grid, the static geometry and the camera."""
    dim = int(_constant("dimensions", 3))
    dp = _constant("dp", 0.01)
    # Materials 0 .. fluids-1 are fluids (phases), the walls follow. The surface drawn is that of
    # phase SPATE_FREE_SURFACE_PHASE (default 0, the first fluid: the water under air).
    fluids = int(_constant("fluids", 1))
    phase = int(os.environ.get("SPATE_FREE_SURFACE_PHASE", "0"))
    fluid.LowerThreshold = fluid.UpperThreshold = min(max(phase, 0), fluids - 1)
    walls.LowerThreshold = fluids
    walls.UpdatePipeline()
    fluid_all.UpdatePipeline()
    wb = walls.GetDataInformation().GetBounds()  # tank with its wall layers (walls never move)

    surface_source = SPHVolumeInterpolator(registrationName="sph", Input=fluid_all, Source="Bounded Volume")
    surface_source.Kernel = "SPHWendlandQuinticKernel"
    surface_source.Kernel.SpatialStep = dp
    surface_source.Kernel.Dimension = dim
    surface_source.ExcludedArrays = ["pressure", "density", "id", "kind", "device", "phase"]
    surface_source.ComputeShepardSum = 1
    surface_source.Source = "Bounded Volume"
    box = surface_source.Source
    box.RefinementMode = "Use cell-size"
    box.CellSize = cell_factor * dp

    if dim == 3:
        # Inside the walls, up to the tank top: the water never leaves it.
        lo = [wb[0], wb[2], wb[4]]
        hi = [wb[1], wb[3], wb[5]]
        box.Origin = lo
        box.Scale = [hi[k] - lo[k] for k in range(3)]
        surface = Contour(registrationName="surface", Input=surface_source)
        surface.ContourBy = ["POINTS", "Shepard Summation"]
        surface.Isosurfaces = [0.5]
        surface.ComputeScalars = 0
        surface.ComputeNormals = 1
        shown = Show(surface, view)
        shown.Specular = 0.4
        shown.SpecularPower = 40.0
        ColorBy(shown, ("POINTS", "velocity", "Magnitude"))
        shown.SetScalarBarVisibility(view, True)
        _fix_speed_range()

        # Static geometry: the floor, the tank outline and the solids, from the wall particles.
        floor = Plane(registrationName="floor")
        floor.Origin = [wb[0], wb[2], wb[4]]
        floor.Point1 = [wb[1], wb[2], wb[4]]
        floor.Point2 = [wb[0], wb[3], wb[4]]
        floor_shown = Show(floor, view)
        floor_shown.AmbientColor = floor_shown.DiffuseColor = [0.55, 0.55, 0.5]
        outline = Outline(registrationName="tank", Input=walls)
        outline_shown = Show(outline, view)
        outline_shown.AmbientColor = outline_shown.DiffuseColor = [0.15, 0.15, 0.15]
        outline_shown.LineWidth = 2.0
        kinds = walls.GetDataInformation().GetPointDataInformation().GetArrayInformation("kind").GetComponentRange(0)
        for kind in range(fluids + 1, int(kinds[1]) + 1):
            solid = Threshold(registrationName="solid_%d" % kind, Input=walls)
            solid.Scalars = ["POINTS", "kind"]
            solid.LowerThreshold = kind
            solid.UpperThreshold = kind
            solid.ThresholdMethod = "Between"
            solid.UpdatePipeline()
            sb = solid.GetDataInformation().GetBounds()
            if sb[0] > sb[1]:
                continue
            block = Box(registrationName="solid_box_%d" % kind)
            block.XLength, block.YLength, block.ZLength = sb[1] - sb[0], sb[3] - sb[2], sb[5] - sb[4]
            block.Center = [(sb[0] + sb[1]) / 2, (sb[2] + sb[3]) / 2, (sb[4] + sb[5]) / 2]
            block_shown = Show(block, view)
            block_shown.AmbientColor = block_shown.DiffuseColor = [0.75, 0.72, 0.66]
        # Three-quarter view from the downstream corner, a little above, like the paper's figure.
        centre = [(wb[0] + wb[1]) / 2, (wb[2] + wb[3]) / 2, (wb[4] + wb[5]) / 2]
        size = max(wb[1] - wb[0], wb[3] - wb[2], wb[5] - wb[4])
        view.CameraFocalPoint = [centre[0], centre[1], wb[4] + 0.15 * (wb[5] - wb[4])]
        view.CameraPosition = [centre[0] + 0.55 * size, centre[1] - 1.05 * size, wb[4] + 0.85 * size]
        view.CameraViewUp = [0, 0, 1]
        view.CameraViewAngle = 30
        view.ResetCamera([wb[0], wb[1], wb[2], wb[3], wb[4], wb[5]], 0.8)
    else:
        # A one-cell-thick slab around z = 0 (the grid may not be flat).
        c = cell_factor * dp
        box.Origin = [wb[0], wb[2], -0.5 * c]
        box.Scale = [wb[1] - wb[0], wb[3] - wb[2], c]
        water = Threshold(registrationName="water", Input=surface_source)
        water.Scalars = ["POINTS", "Shepard Summation"]
        water.LowerThreshold = 0.5
        water.UpperThreshold = 1.0e30
        water.ThresholdMethod = "Between"
        water.AllScalars = 0
        shown = Show(water, view)
        ColorBy(shown, ("POINTS", "velocity", "Magnitude"))
        shown.SetScalarBarVisibility(view, True)
        _fix_speed_range()
        wall_shown = Show(walls, view)
        wall_shown.SetRepresentationType("Points")
        wall_shown.PointSize = 2.0
        wall_shown.ColorArrayName = [None, ""]
        wall_shown.AmbientColor = wall_shown.DiffuseColor = [0.3, 0.3, 0.3]
        view.InteractionMode = "2D"
        view.CameraParallelProjection = 1
        view.CameraPosition = [(wb[0] + wb[1]) / 2, (wb[2] + wb[3]) / 2, 1.0]
        view.CameraFocalPoint = [(wb[0] + wb[1]) / 2, (wb[2] + wb[3]) / 2, 0.0]
        view.CameraViewUp = [0, 1, 0]
        view.ResetCamera([wb[0], wb[1], wb[2], wb[3], -0.01, 0.01], 0.95)
    return surface_source


def catalyst_execute(info):
    global _scene
    particles.UpdatePipeline(info.time)
    if _scene is None:
        _scene = _build_scene()
