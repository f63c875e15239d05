"""Readers for a spate run folder, shared by the plot scripts: a probe CSV as a numeric table, the
saved steps and their times, and the particle arrays of one saved step (every slab's piece)."""
import csv
import re

import numpy as np
from vtk.util.numpy_support import vtk_to_numpy
import vtk


def probe_table(path):
    """The probe file's rows (time, step, values...) as a 2D float array, header dropped."""
    with open(path) as f:
        rows = list(csv.reader(f))[1:]
    return np.array([[float(v) for v in r] for r in rows])


def saved_steps(run):
    """(time, step folder) of every saved step, in the order of the run's ParaView collection
    (particles.pvd)."""
    entries = re.findall(r'timestep="([^"]+)"[^>]*file="([^"]+)\.vtm"', (run / "particles.pvd").read_text())
    return [(float(t), run / f) for t, f in entries]


def saved_step_near(run, t):
    """(time, step folder) of the saved step nearest to time t [s]."""
    return min(saved_steps(run), key=lambda e: abs(e[0] - t))


def snapshot_arrays(step_dir, names):
    """Positions (n x 3) and the named point arrays of one saved step, its slabs concatenated;
    a name the files do not hold comes back as None."""
    points, arrays = [], {n: [] for n in names}
    for piece in sorted(step_dir.glob("*.vtp")):
        r = vtk.vtkXMLPolyDataReader()
        r.SetFileName(str(piece))
        r.Update()
        d = r.GetOutput()
        points.append(vtk_to_numpy(d.GetPoints().GetData()))
        for n in names:
            a = d.GetPointData().GetArray(n)
            arrays[n].append(vtk_to_numpy(a) if a is not None else None)
    out = {n: (None if any(a is None for a in v) else np.concatenate(v)) for n, v in arrays.items()}
    return np.concatenate(points), out
