# script-version: 2
# spate in-situ pipeline: the free surface, reconstructed from the particles and rendered off screen.
#
# The fluid particles are interpolated with an SPH kernel onto a regular grid that covers the tank
# (ParaView's SPH Volume Interpolator, Wendland kernel, spatial step dp, so that the Shepard sum
# S = sum_j W_ij dp^d is 1 inside the water and 0 outside); the surface is the Shepard sum's 0.5
# contour. It is coloured by the Shepard-normalised field, sum_j f_j W_ij dp^d / S (the SPH
# estimate of f; without the division a field reads half its value on the 0.5 contour), by default
# the speed |v|. The tank floor, its outline and every solid (the column) are drawn too, from a
# three-quarter view like the paper's Figure 4, with the simulated time in a corner; a solid of any
# shape (a mesh, a cylinder) from the surface spate wrote for it (<run output>/geometry/), a static
# box solid as the box its particles fill; a tank of any shape (tank: {mesh: ...}) from its surface
# (geometry/tank.vtp), translucent. A moving solid (prescribed or floating; its box too) is
# drawn where it is now: at every step the rigid motion that carries its particles from their start
# (geometry/solid_<kind>_start.vtp) to where they are (least squares, Kabsch 1976) places its
# surface, turned and shifted as the body is. In 2D the
# water is the region where the Shepard sum exceeds 0.5, seen from the front.
# PNGs go to <run output>/insitu/free_surface_<step>.png.
#
# Environment (scripts take no arguments):
#   SPATE_INSITU_IMAGE_SIZE=WxH      image size (default 1200x800)
#   SPATE_FREE_SURFACE_CELL=c        grid cell in units of dp (default 1; larger is faster: cost
#                                    about 25 us per grid point on 2 cores)
#   SPATE_FREE_SURFACE_ARRAY=name    the point array to colour by (default velocity, shown as
#                                    speed; vectors by magnitude): velocity, pressure, density, ...
#   SPATE_FREE_SURFACE_RANGE=lo,hi   its colour range (default 0,3 m/s for the speed; else the
#                                    data's range at each step)
#   SPATE_FREE_SURFACE_DATA=1        also write the coloured surface (3D, .vtp) or water region
#                                    (2D, .vtu) with its values: insitu/free_surface_<step>.vt?
#   SPATE_FREE_SURFACE_PHASE=k       with several fluids, the surface of fluid k (default 0, the
#                                    first: the water under air or oil)
# Case constants come from the dataset's field data (dp, dimensions), put there by spate.
# The colour map belongs to this script alone (a separate colour map): other pipelines in the same
# run cannot change it.
import os

import numpy as np
from paraview.simple import *
from paraview import catalyst
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonMath import vtkMatrix4x4
from vtkmodules.vtkCommonTransforms import vtkTransform

width, height = (int(v) for v in os.environ.get("SPATE_INSITU_IMAGE_SIZE", "1200x800").split("x"))
cell_factor = float(os.environ.get("SPATE_FREE_SURFACE_CELL", "1.0"))
coloured = os.environ.get("SPATE_FREE_SURFACE_ARRAY", "velocity")
write_data = os.environ.get("SPATE_FREE_SURFACE_DATA", "0") == "1"
TITLES = {"velocity": "speed [m/s]", "pressure": "pressure [Pa]", "density": "density [kg/m3]"}
value_name = "speed" if coloured == "velocity" else coloured + "_normalised"
value_range = os.environ.get("SPATE_FREE_SURFACE_RANGE", "0,3" if coloured == "velocity" else "")
value_range = [float(v) for v in value_range.split(",")] if value_range else None

particles = TrivialProducer(registrationName="particles")
run_dir = os.environ.get("SPATE_RUN_DIR", ".")  # the run's output folder (spate sets it)

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

# The simulated time (and the step), updated at every in-situ step.
clock = Text(registrationName="clock")
clock_shown = Show(clock, view)
clock_shown.WindowLocation = "Upper Left Corner"
clock_shown.Color = [0.05, 0.05, 0.05]
clock_shown.FontSize = max(10, height // 40)

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


def _colour(shown):
    """Colours by the normalised value with this script's own colour map (Jet) and scale bar."""
    ColorBy(shown, ("POINTS", value_name), separate=True)
    lut = shown.LookupTable
    lut.ApplyPreset("Jet", True)
    if value_range:
        # A fixed range keeps images comparable over time (after ColorBy, which rescales to the data).
        lut.AutomaticRescaleRangeMode = "Never"
        lut.RescaleTransferFunction(*value_range)
    else:
        lut.AutomaticRescaleRangeMode = "Grow and update every timestep"
    bar = GetScalarBar(lut, view)
    bar.Title = TITLES.get(coloured, coloured)
    bar.ComponentTitle = ""
    bar.WindowLocation = "Any Location"
    bar.Position = [0.89, 0.05]
    bar.ScalarBarLength = 0.33
    shown.SetScalarBarVisibility(view, True)


def _normalised(interpolated):
    """The interpolated field divided by the Shepard sum (0 where no particle is in reach)."""
    calc = Calculator(registrationName="normalised", Input=interpolated)
    calc.ResultArrayName = value_name
    vector = fluid_all.PointData[coloured].GetNumberOfComponents() > 1
    calc.Function = ("mag(%s)" if vector else "%s") % coloured + "/max(shepard,1e-6)"
    return calc


# The box solids, each as (its particles, the box drawn for it): refitted at every step, so that a
# moving one (a wave paddle, a floating box) is drawn where it is now.
_boxes = []


def _fit_box(block, b):
    """The drawn box made the bounding box b of a solid's particles."""
    block.XLength, block.YLength, block.ZLength = b[1] - b[0], b[3] - b[2], b[5] - b[4]
    block.Center = [(b[0] + b[1]) / 2, (b[2] + b[3]) / 2, (b[4] + b[5]) / 2]


# The moving solids, each as (its particles, the Transform that places its surface, its particles'
# ids and positions at the start, sorted by id).
_posed = []


def _ids_and_points(source):
    """The ids and positions of a source's points, sorted by id."""
    data = source.GetClientSideObject().GetOutputDataObject(0)
    if data is None or data.GetNumberOfPoints() == 0:
        return np.zeros(0, np.int64), np.zeros((0, 3))
    ids = vtk_to_numpy(data.GetPointData().GetArray("id")).astype(np.int64)
    x = vtk_to_numpy(data.GetPoints().GetData()).astype(np.float64)
    order = np.argsort(ids, kind="stable")
    return ids[order], x[order]


def _rigid_fit(x0, x):
    """The rotation R and translation t that carry points x0 closest to x (x ~ R x0 + t; Kabsch)."""
    c0, c = x0.mean(axis=0), x.mean(axis=0)
    u, _, vt = np.linalg.svd((x0 - c0).T @ (x - c))
    d = 1.0 if np.linalg.det(vt.T @ u.T) >= 0 else -1.0
    r = vt.T @ np.diag([1.0, 1.0, d]) @ u.T
    return r, c - r @ c0


def _place(entry, time):
    """Moves a solid's surface to the pose its particles have now."""
    particles_now, placed, ids0, x0 = entry
    particles_now.UpdatePipeline(time)
    ids, x = _ids_and_points(particles_now)
    _, at0, at = np.intersect1d(ids0, ids, assume_unique=True, return_indices=True)
    if len(at) < 4:
        return
    r, t = _rigid_fit(x0[at0], x[at])
    m = vtkMatrix4x4()
    for i in range(3):
        for j in range(3):
            m.SetElement(i, j, r[i, j])
    turn = vtkTransform()
    turn.SetMatrix(m)
    # ParaView's Transform applies Translate after RotateZ, RotateX, RotateY (vtkProp3D's order),
    # which is how vtkTransform reports an orientation.
    placed.Transform.Rotate = list(turn.GetOrientation())
    placed.Transform.Translate = [float(v) for v in t]


def _posed_solid(kind, particles_of_solid, surface, start_file):
    """The surface of a moving solid, placed at every step where its particles are."""
    start = XMLPolyDataReader(registrationName="solid_start_%d" % kind, FileName=[start_file])
    start.UpdatePipeline()
    ids0, x0 = _ids_and_points(start)
    placed = Transform(registrationName="solid_placed_%d" % kind, Input=surface)
    placed.Transform = "Transform"
    entry = (MergeBlocks(registrationName="solid_merged_%d" % kind, Input=particles_of_solid), placed, ids0, x0)
    _posed.append(entry)
    return entry


def _build_scene(time):
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
    if coloured not in fluid_all.PointData.keys():
        raise RuntimeError("SPATE_FREE_SURFACE_ARRAY=%s: no such point array (there are %s)"
                           % (coloured, ", ".join(fluid_all.PointData.keys())))

    surface_source = SPHVolumeInterpolator(registrationName="sph", Input=fluid_all, Source="Bounded Volume")
    surface_source.Kernel = "SPHWendlandQuinticKernel"
    surface_source.Kernel.SpatialStep = dp
    surface_source.Kernel.Dimension = dim
    surface_source.ExcludedArrays = [a for a in fluid_all.PointData.keys() if a != coloured]
    surface_source.ComputeShepardSum = 1
    surface_source.ShepardSumArrayName = "shepard"
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
        surface = Contour(registrationName="surface", Input=_normalised(surface_source))
        surface.ContourBy = ["POINTS", "shepard"]
        surface.Isosurfaces = [0.5]
        surface.ComputeScalars = 1
        surface.ComputeNormals = 1
        shown = Show(surface, view)
        shown.Specular = 0.4
        shown.SpecularPower = 40.0
        _colour(shown)

        # Static geometry: the floor, the tank outline and the solids, from the wall particles; a
        # tank of any shape (a vessel from a mesh) from its surface, translucent, where it is now.
        tank_file = os.path.join(run_dir, "geometry", "tank.vtp")
        if os.path.exists(tank_file):
            vessel = XMLPolyDataReader(registrationName="tank_surface", FileName=[tank_file])
            tank_start = os.path.join(run_dir, "geometry", "tank_start.vtp")
            if os.path.exists(tank_start):
                tank_walls = Threshold(registrationName="tank_walls", Input=walls)
                tank_walls.Scalars = ["POINTS", "kind"]
                tank_walls.LowerThreshold = tank_walls.UpperThreshold = fluids
                tank_walls.ThresholdMethod = "Between"
                entry = _posed_solid(fluids, tank_walls, vessel, tank_start)
                _place(entry, time)
                vessel = entry[1]
            vessel_shown = Show(vessel, view)
            vessel_shown.AmbientColor = vessel_shown.DiffuseColor = [0.75, 0.72, 0.66]
            vessel_shown.Opacity = 0.3
        else:
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
            # A solid of any shape (a mesh, a cylinder, ...) is drawn from the surface spate wrote
            # for it; a box solid as the box its particles fill.
            surface_file = os.path.join(run_dir, "geometry", "solid_%d.vtp" % kind)
            start_file = os.path.join(run_dir, "geometry", "solid_%d_start.vtp" % kind)
            if os.path.exists(surface_file):
                block = XMLPolyDataReader(registrationName="solid_surface_%d" % kind, FileName=[surface_file])
                if os.path.exists(start_file):
                    entry = _posed_solid(kind, solid, block, start_file)
                    _place(entry, time)
                    block = entry[1]
            else:
                block = Box(registrationName="solid_box_%d" % kind)
                _fit_box(block, sb)
                _boxes.append((solid, block))
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
        surface = Threshold(registrationName="water", Input=_normalised(surface_source))
        surface.Scalars = ["POINTS", "shepard"]
        surface.LowerThreshold = 0.5
        surface.UpperThreshold = 1.0e30
        surface.ThresholdMethod = "Between"
        surface.AllScalars = 0
        shown = Show(surface, view)
        _colour(shown)
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
    if write_data:
        data = CreateExtractor("VTP" if dim == 3 else "VTU", surface, registrationName="free_surface_data")
        data.Trigger = "TimeStep"
        data.Trigger.Frequency = 1
        data.Writer.FileName = "free_surface_{timestep:06d}." + ("vtp" if dim == 3 else "vtu")
    return surface_source


def catalyst_execute(info):
    global _scene
    particles.UpdatePipeline(info.time)
    clock.Text = "t = %.3f s   (step %d)" % (info.time, info.timestep)
    if _scene is None:
        _scene = _build_scene(info.time)
    else:
        for entry in _posed:
            _place(entry, info.time)
        for solid, block in _boxes:
            solid.UpdatePipeline(info.time)
            b = solid.GetDataInformation().GetBounds()
            if b[0] <= b[1]:
                _fit_box(block, b)
