#!/usr/bin/env bash
# The Catalyst adaptor under MPI: 2 ranks x 2 devices run the 2D dam break with pipelines/extract.py;
# the extract of the last in-situ step must hold 4 blocks (one per device) whose particles add up to
# the case's particle count, with every id present once.
# Usage: mpi_extract.sh SPATE SOURCE_DIR OUT_DIR
set -euo pipefail
spate=$1 src=$2 out=$3
rm -rf "$out"
mkdir -p "$out"
export OMPI_MCA_mpi_yield_when_idle=1 OMPI_MCA_rmaps_base_oversubscribe=1
timeout 300 mpirun --allow-run-as-root --oversubscribe -np 2 "$spate" run "$src/cases/dam_break_2d.yaml" \
  --out "$out/run" --steps 4 --devices 2 --insitu-every 2 --pipeline "$src/pipelines/extract.py" \
  --set output.interval=0 --set probes=[] --quiet >"$out/run.log" 2>&1 || { cat "$out/run.log"; exit 1; }
total=$("$spate" info "$src/cases/dam_break_2d.yaml" --json | /usr/bin/python3 -c "import json,sys; print(json.load(sys.stdin)['particles']['total'])")
last=$(ls "$out"/run/insitu/particles_*.vtm | sort | tail -n 1)
pvpython - "$last" "$total" <<'PY'
import sys
from paraview.vtk.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkIOXML import vtkXMLMultiBlockDataReader
import numpy as np
path, total = sys.argv[1], int(sys.argv[2])
r = vtkXMLMultiBlockDataReader()
r.SetFileName(path)
r.Update()
mb = r.GetOutput()
ids, devices = [], set()
it = mb.NewIterator()
it.InitTraversal()
blocks = 0
while not it.IsDoneWithTraversal():
    ds = it.GetCurrentDataObject()
    blocks += 1
    ids.append(vtk_to_numpy(ds.GetPointData().GetArray("id")))
    devices.update(np.unique(vtk_to_numpy(ds.GetPointData().GetArray("device"))).tolist())
    it.GoToNextItem()
ids = np.concatenate(ids)
print(f"{path}: {blocks} blocks, devices {sorted(devices)}, {ids.size} particles (case: {total})")
assert blocks == 4, "one block per device expected"
assert sorted(devices) == [0, 1, 2, 3], "every device must appear"
assert ids.size == total and np.unique(ids).size == total, "every particle exactly once"
print("PASS")
PY
