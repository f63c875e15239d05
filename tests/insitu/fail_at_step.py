# script-version: 2
# Test pipeline: loads fine, then raises at the step given by SPATE_FAIL_AT_STEP (default 2).
import os

from paraview.simple import *
from paraview import catalyst

particles = TrivialProducer(registrationName="particles")
options = catalyst.Options()
fail_at = int(os.environ.get("SPATE_FAIL_AT_STEP", "2"))


def catalyst_execute(info):
    particles.UpdatePipeline(info.time)
    if info.timestep >= fail_at:
        raise RuntimeError("deliberate failure at step %d" % info.timestep)
