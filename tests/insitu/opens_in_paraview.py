"""What a run leaves on disk opens in ParaView (pvpython), as a user would open it:
a checkpoint through its XDMF sidecar with OpenDataFile (every particle, every exported array),
and the snapshot series (particles.pvd) with one block per slab named slab_<k>, like the in-situ
dataset's, and the case constants in the field data that pipelines read.

    pvpython opens_in_paraview.py SPATE SOURCE_DIR WORK_DIR
"""
import json
import os
import shutil
import subprocess
import sys

from paraview.simple import OpenDataFile, servermanager

spate, src, work = sys.argv[1:4]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
failures = []


def check(cond, what):
    if not cond:
        failures.append(what)
        print("FAIL: " + what)


out = os.path.join(work, "run")
subprocess.run([spate, "run", os.path.join(src, "cases", "dam_break_2d.yaml"), "--steps", "10", "--devices", "2",
                "--set", "output.interval=1", "--checkpoint-every", "5", "--out", out, "--quiet"], check=True)
particles = json.load(open(os.path.join(out, "summary.json")))["particles"]["total"]

# The checkpoint, opened by its sidecar.
for step in (5, 10):
    reader = OpenDataFile(os.path.join(out, "checkpoints", "checkpoint_step_%08d.xmf2" % step))
    check(reader is not None, "no reader for the checkpoint's .xmf2")
    reader.UpdatePipeline()
    data = servermanager.Fetch(reader)
    check(data.GetNumberOfPoints() == particles, "checkpoint %d: %d points, the run has %d particles" % (step, data.GetNumberOfPoints(), particles))
    arrays = {data.GetPointData().GetArrayName(i) for i in range(data.GetPointData().GetNumberOfArrays())}
    check({"velocity", "pressure", "density", "id", "kind"} <= arrays, "checkpoint arrays %s" % sorted(arrays))
    ids = data.GetPointData().GetArray("id").GetRange(0)
    check(ids == (0.0, particles - 1.0), "checkpoint ids %s" % (ids,))

# The snapshot series: the last step, both slabs' blocks, the case constants.
series = OpenDataFile(os.path.join(out, "particles.pvd"))
series.UpdatePipeline(max(series.TimestepValues))
data = servermanager.Fetch(series)
names = [data.GetMetaData(k).Get(data.NAME()) for k in range(data.GetNumberOfBlocks())]
check(names == ["slab_0", "slab_1"], "snapshot block names %s" % names)
check(sum(data.GetBlock(k).GetNumberOfPoints() for k in range(data.GetNumberOfBlocks())) == particles, "snapshot particle count")
fields = data.GetFieldData()
constants = {fields.GetArrayName(k): fields.GetArray(k).GetValue(0) for k in range(fields.GetNumberOfArrays())}
check(constants.get("dp") == 0.002 and constants.get("dimensions") == 2 and constants.get("step") == 10, "snapshot field data %s" % constants)
print("checkpoints and snapshots open in ParaView: %s" % ("OK" if not failures else "%d failures" % len(failures)))
sys.exit(1 if failures else 0)
