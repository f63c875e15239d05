# script-version: 2
# spate in-situ pipeline: particle extracts for later analysis. Every in-situ step writes the
# particles of all devices as one multiblock file (one block per device, ParaView's .vtm with
# .vtp pieces) to <run output>/insitu/particles_<step>.vtm, with every array spate provides
# (velocity, pressure, density, id, kind, device). Open the series in ParaView as a time series.
from paraview.simple import *
from paraview import catalyst

particles = TrivialProducer(registrationName="particles")

vtm = CreateExtractor("VTM", particles, registrationName="particles_vtm")
vtm.Trigger = "TimeStep"
vtm.Trigger.Frequency = 1
vtm.Writer.FileName = "particles_{timestep:06d}.vtm"

options = catalyst.Options()
options.ExtractsOutputDirectory = "insitu"
options.GlobalTrigger = "TimeStep"


def catalyst_execute(info):
    particles.UpdatePipeline(info.time)
