"""pipelines/free_surface.py against the particles it draws (ctest label `image`; run with pvpython).

The 2D dam break at dp = 0.004 m is run to step 1000 (t = 0.092 s, the front running out at about
1.5 m/s) twice, spate rendering free_surface.py at 400x300:
  A. with extract.py (the particles) and SPATE_FREE_SURFACE_DATA=1 (the coloured water region with
     its values);
  B. together with particles.py (another colour map, Turbo, in the same in-situ process).
Checks:
  1. the colours are the Shepard-normalised speed: at the grid points near the surface (Shepard sum
     0.25 to 0.75) the values free_surface.py coloured match |sum_j v_j W_j| / sum_j W_j computed
     here from the extracted fluid particles (the same Wendland kernel, h = dp, support 2h) within
     5 %, point by point and in their range (without the division they read about half);
  2. the free-surface image is the same alone and with particles.py (each pipeline owns its colour
     map; it used to switch from Jet to Turbo);
  3. the in-situ index lists both images of each run with step 1000 and the simulated time.

Usage: pvpython free_surface_check.py SPATE SOURCE_DIR WORK_DIR
"""
import csv
import os
import shutil
import subprocess
import sys

import numpy as np
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkIOXML import vtkXMLMultiBlockDataReader, vtkXMLPUnstructuredGridReader
from vtkmodules.vtkTestingRendering import vtkTesting

spate, src, work = sys.argv[1:4]
STEP, DP = 1000, 0.004


def fail(msg):
    print("FAIL:", msg, flush=True)
    sys.exit(1)


def run(name, pipelines, env_extra):
    out = os.path.join(work, name)
    shutil.rmtree(out, ignore_errors=True)
    env = dict(os.environ, SPATE_INSITU_IMAGE_SIZE="400x300", **env_extra)
    cmd = [spate, "run", os.path.join(src, "cases", "dam_break_2d.yaml"), "--out", out, "--steps", str(STEP),
           "--insitu-every", str(STEP), "--set", f"dp={DP}", "--set", "output.interval=0", "--set", "probes=[]",
           "--checkpoint-every", "0", "--quiet"]
    for p in pipelines:
        cmd += ["--pipeline", os.path.join(src, "pipelines", p)]
    r = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=600)
    if r.returncode != 0:
        fail(f"{name}: exit {r.returncode}:\n{r.stderr[-3000:]}")
    return out


def index_rows(out):
    with open(os.path.join(out, "insitu", "index.csv")) as f:
        return list(csv.DictReader(f))


shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
a = run("alone", ["free_surface.py", "extract.py"], {"SPATE_FREE_SURFACE_DATA": "1"})
b = run("with_particles", ["free_surface.py", "particles.py"], {})
image = f"insitu/free_surface_{STEP:06d}.png"

# 1. Colours = Shepard-normalised speed.
reader = vtkXMLPUnstructuredGridReader()  # ParaView writes the extract as a parallel file
reader.SetFileName(os.path.join(a, "insitu", f"free_surface_{STEP:06d}.vtu"))
reader.Update()
region = reader.GetOutput()
grid = vtk_to_numpy(region.GetPoints().GetData()).astype(np.float64)
coloured = vtk_to_numpy(region.GetPointData().GetArray("speed")).astype(np.float64)
shepard = vtk_to_numpy(region.GetPointData().GetArray("shepard")).astype(np.float64)

mb = vtkXMLMultiBlockDataReader()
mb.SetFileName(os.path.join(a, "insitu", f"particles_{STEP:06d}.vtm"))
mb.Update()
xs, vs = [], []
it = mb.GetOutput().NewIterator()
it.InitTraversal()
while not it.IsDoneWithTraversal():
    block = it.GetCurrentDataObject()
    fluid = vtk_to_numpy(block.GetPointData().GetArray("kind")) == 0
    xs.append(vtk_to_numpy(block.GetPoints().GetData())[fluid])
    vs.append(vtk_to_numpy(block.GetPointData().GetArray("velocity"))[fluid])
    it.GoToNextItem()
x = np.concatenate(xs).astype(np.float64)
v = np.concatenate(vs).astype(np.float64)

surface = (shepard >= 0.25) & (shepard <= 0.75)
points = grid[surface]
q = np.linalg.norm(points[:, None, :] - x[None, :, :], axis=2) / DP
w = np.where(q < 2.0, (1.0 - 0.5 * q) ** 4 * (1.0 + 2.0 * q), 0.0)  # Wendland (quintic) shape, h = dp
sums = w.sum(axis=1)
reference = np.linalg.norm(w @ v, axis=1) / np.maximum(sums, 1e-300)
raw = np.linalg.norm(w @ v, axis=1) * (7.0 / (4.0 * np.pi * DP**2)) * DP**2  # S-weighted, not normalised
seen = coloured[surface]
print(f"{surface.sum()} grid points near the surface; fluid speed up to {np.linalg.norm(v, axis=1).max():.3f} m/s")
print(f"coloured speed there: {seen.min():.3f} to {seen.max():.3f} m/s; Shepard-normalised from the particles: "
      f"{reference.min():.3f} to {reference.max():.3f} m/s; unnormalised interpolation up to {raw.max():.3f} m/s")
if surface.sum() < 20:
    fail("too few surface points to compare")
if abs(seen.max() - reference.max()) > 0.05 * reference.max():
    fail(f"the coloured speed range ends at {seen.max():.4f} m/s, the Shepard-normalised speed at {reference.max():.4f}")
moving = reference > 0.05 * reference.max()
worst = np.max(np.abs(seen[moving] - reference[moving]) / reference[moving])
print(f"largest point-by-point difference {100 * worst:.3f} %")
if worst > 0.05:
    fail(f"coloured speed differs from the Shepard-normalised speed by up to {100 * worst:.1f} %")

# 2. The same free-surface image with particles.py in the same run.
testing = vtkTesting()
for arg in ("-T", work, "-V", os.path.join(a, image)):
    testing.AddArgument(arg)
if testing.RegressionTest(os.path.join(b, image), 0.15) != vtkTesting.PASSED:
    fail(f"{image} differs when particles.py runs too (difference image in {work})")
same = open(os.path.join(a, image), "rb").read() == open(os.path.join(b, image), "rb").read()
print(f"free-surface image alone and with particles.py: {'byte-identical' if same else 'within the image tolerance'}")

# 3. The index lists each image with its step and time.
for out, files in ((a, [image]), (b, [image, f"insitu/particles_{STEP:06d}.png"])):
    rows = {r["file"]: r for r in index_rows(out)}
    for f in files:
        if f not in rows or int(rows[f]["step"]) != STEP or not 0.09 < float(rows[f]["time[s]"]) < 0.095:
            fail(f"{out}/insitu/index.csv does not list {f} at step {STEP}, t = 0.092 s: {rows.get(f)}")
print("free surface: OK")
