# script-version: 2
# spate Catalyst Live: connects OUT to a ParaView that listens (GUI: Catalyst > Connect; or a
# pvpython client using paraview.live) on every in-situ step, and retries on the next in-situ step
# while nobody listens. `spate run CASE --live [HOST:]PORT` adds this script; it reads the address
# from SPATE_LIVE_URL (default localhost:22222). The simulation never opens a listening socket.
#
# What the client sees in the Catalyst pipeline browser:
#   particles  the simulation's particles (all kinds; point data kind, velocity, pressure, density,
#              id; one block per device), the channel of the same name;
#   steering   spate's steering parameters (pipelines/spate_steering.xml), created by the simulation.
# Pausing in the client (Catalyst > Pause Simulation) holds the simulation inside this step.
import os

from paraview.simple import *
from paraview import catalyst

particles = TrivialProducer(registrationName="particles")

options = catalyst.Options()
options.EnableCatalystLive = 1
options.CatalystLiveURL = os.environ.get("SPATE_LIVE_URL", "localhost:22222")
# Every step this script is run on is a live step (spate decides how often: --insitu-every).
options.CatalystLiveTrigger = "TimeStep"
options.CatalystLiveTrigger.Frequency = 1


def catalyst_execute(info):
    particles.UpdatePipeline(info.time)
