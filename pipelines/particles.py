# script-version: 2
# spate in-situ pipeline: the fluid particles as point sprites coloured by speed, with the
# simulated time in a corner, written as PNGs to <run output>/insitu/particles_<step>.png. A
# standard ParaView Catalyst v2 script: the source named 'particles' is bound to the simulation's
# channel of the same name. Its colour map (Turbo) is its own (a separate colour map): other
# pipelines in the same run cannot change it, nor it theirs.
# Environment: SPATE_INSITU_IMAGE_SIZE=WxH (default 800x600).
import os

from paraview.simple import *
from paraview import catalyst

width, height = (int(v) for v in os.environ.get("SPATE_INSITU_IMAGE_SIZE", "800x600").split("x"))

particles = TrivialProducer(registrationName="particles")

# kind 0 is fluid; walls and solids are 1 and above.
fluid = Threshold(registrationName="fluid", Input=particles)
fluid.Scalars = ["POINTS", "kind"]
fluid.LowerThreshold = 0
fluid.UpperThreshold = 0
fluid.ThresholdMethod = "Between"

view = CreateView("RenderView")
view.ViewSize = [width, height]
view.OrientationAxesVisibility = 0
view.Background = [1.0, 1.0, 1.0]
view.UseColorPaletteForBackground = 0

display = Show(fluid, view)
display.SetRepresentationType("Point Gaussian")
display.ShaderPreset = "Sphere"
display.GaussianRadius = 0.004
ColorBy(display, ("POINTS", "velocity", "Magnitude"), separate=True)
speed = display.LookupTable
speed.ApplyPreset("Turbo", True)
speed.RescaleTransferFunction(0.0, 3.0)
speed.AutomaticRescaleRangeMode = "Never"
bar = GetScalarBar(speed, view)
bar.Title = "speed [m/s]"
bar.ComponentTitle = ""
bar.TitleColor = bar.LabelColor = [0.1, 0.1, 0.1]
display.SetScalarBarVisibility(view, True)

# The simulated time (and the step), updated at every in-situ step.
clock = Text(registrationName="clock")
clock_shown = Show(clock, view)
clock_shown.WindowLocation = "Upper Left Corner"
clock_shown.Color = [0.1, 0.1, 0.1]
clock_shown.FontSize = max(10, height // 40)

png = CreateExtractor("PNG", view, registrationName="particles_png")
png.Trigger = "TimeStep"
png.Trigger.Frequency = 1
png.Writer.FileName = "particles_{timestep:06d}.png"
png.Writer.ImageResolution = [width, height]

options = catalyst.Options()
options.ExtractsOutputDirectory = "insitu"
options.GlobalTrigger = "TimeStep"

_camera_set = False


def catalyst_execute(info):
    global _camera_set
    particles.UpdatePipeline(info.time)
    clock.Text = "t = %.3f s   (step %d)" % (info.time, info.timestep)
    if not _camera_set:
        # The whole tank, seen from the front (2D) or three-quarters (3D), fixed for the run.
        bounds = particles.GetDataInformation().GetBounds()
        view.ResetCamera(bounds)
        if bounds[5] - bounds[4] > 1e-9:
            cx, cy, cz = [(bounds[2 * k] + bounds[2 * k + 1]) / 2 for k in range(3)]
            size = max(bounds[1] - bounds[0], bounds[3] - bounds[2], bounds[5] - bounds[4])
            view.CameraFocalPoint = [cx, cy, cz]
            view.CameraPosition = [cx + 0.9 * size, cy - 1.3 * size, cz + 0.9 * size]
            view.CameraViewUp = [0, 0, 1]
            view.ResetCamera(bounds)
        _camera_set = True
