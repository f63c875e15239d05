# script-version: 2
# Test pipeline: records what the pipeline receives on channel 'particles' -- the addresses of the
# raw buffers behind every array (the components of the position and velocity arrays, which are
# structure-of-arrays, and the single-component arrays; neither lookup copies), and every
# particle's values -- so that the C++ test can compare them with the solver's buffers.
# Output: $SPATE_RECORD_DIR/step_<n>.json and step_<n>.csv.
import json
import os

from paraview.simple import *
from paraview import catalyst

particles = TrivialProducer(registrationName="particles")
options = catalyst.Options()
out = os.environ["SPATE_RECORD_DIR"]


def _address(text):
    # VTK's Python wrapping prints pointers as '_<hex>_p_<type>'.
    return int(str(text).split("_")[1], 16)


def catalyst_execute(info):
    particles.UpdatePipeline(info.time)
    data = particles.GetClientSideObject().GetOutputDataObject(0)
    record = {"step": info.timestep, "pid": os.getpid(), "blocks": []}
    rows = []
    for b in range(data.GetNumberOfBlocks()):
        block = data.GetBlock(b)
        if block is None:
            continue
        pd = block.GetPointData()
        points = block.GetPoints().GetData()
        vel = pd.GetArray("velocity")
        entry = {"block": b, "n": block.GetNumberOfPoints(), "soa": points.GetArrayType() == points.SoADataArrayTemplate and vel.GetArrayType() == vel.SoADataArrayTemplate}
        for k, axis in enumerate("xyz"):
            entry[axis + "_buffer"] = _address(points.GetComponentArrayPointer(k))
            entry["v" + axis + "_buffer"] = _address(vel.GetComponentArrayPointer(k))
        for name in ("pressure", "density", "id", "kind", "device"):
            entry[name + "_buffer"] = _address(pd.GetArray(name).GetVoidPointer(0))
        record["blocks"].append(entry)
        p, rho = pd.GetArray("pressure"), pd.GetArray("density")
        ids, kind, dev = pd.GetArray("id"), pd.GetArray("kind"), pd.GetArray("device")
        for i in range(block.GetNumberOfPoints()):
            x = points.GetTuple3(i)
            v = vel.GetTuple3(i)
            rows.append("%d,%r,%r,%r,%r,%r,%r,%r,%r,%d,%d" % (ids.GetValue(i), x[0], x[1], x[2], v[0], v[1], v[2],
                                                         p.GetValue(i), rho.GetValue(i), kind.GetValue(i), dev.GetValue(i)))
    with open(os.path.join(out, "step_%d.json" % info.timestep), "w") as f:
        json.dump(record, f)
    with open(os.path.join(out, "step_%d.csv" % info.timestep), "w") as f:
        f.write("\n".join(rows) + "\n")
