# script-version: 2
# Test pipeline: fails while it is imported (a typo in a filter name).
from paraview.simple import *
from paraview import catalyst

particles = TrivialProducer(registrationName="particles")
broken = NoSuchFilterInParaView(Input=particles)
options = catalyst.Options()


def catalyst_execute(info):
    pass
