#!/usr/bin/env /usr/bin/python3
"""Figures of the Rayleigh-Taylor validation (docs/validation.md, docs/studies/rayleigh-taylor.md).
--linear: the interface amplitude of runs of cases/rayleigh_taylor_linear_2d.yaml (LABEL=RUN, e.g.
the folders the validation test leaves in /tmp/spate-test-*-rt-linear-0.02) against viscous linear
theory from rest, a(t) = a0 (n' e^(n t) + n e^(-n' t)) / (n + n'), n and -n' the roots of
a'' + 2 nu k^2 a' - A g k a = 0; each run's fitted rate from `spate growth --json` (the same fit as
the test) in the legend. --large: the snapshots of a run of cases/rayleigh_taylor_2d.yaml at
t = 1, 3, 5, particles coloured by fluid.
Usage: scripts/studies/rayleigh_taylor_plots.py [--linear LABEL=RUN ...] [--large RUN]
                                                [--spate build/bin/spate] [--out DIR (default docs/images)]"""
import argparse
import glob
import json
import math
import os
import subprocess
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

ATWOOD, G, K, NU = 0.8 / 2.8, 1.0, 2 * math.pi, 1.0 / 420
UNTIL = 0.03  # k a = 0.19: the linear range the test fits


def theory(t, a0):
    root = math.sqrt(ATWOOD * G * K + (NU * K * K) ** 2)
    n, m = root - NU * K * K, root + NU * K * K
    return a0 * (m * np.exp(n * t) + n * np.exp(-m * t)) / (n + m), n


def probe(run):
    d = np.genfromtxt(run + "/probes/amplitude.csv", delimiter=",", names=True)
    return d["times"], d["amplitudem"]


def linear(runs, spate, out):
    fig, ax = plt.subplots(figsize=(8, 5))
    t_all = None
    for label, run in runs:
        t, a = probe(run)
        fit = json.loads(subprocess.run([spate, "growth", run + "/probes/amplitude.csv", "--until", str(UNTIL), "--json"],
                                        check=True, capture_output=True, text=True).stdout)
        ax.semilogy(t, a, label=f"{label}: n = {fit['rate']:.3f}" if fit["rms"] < 0.05 else f"{label} (no exponential growth)")
        if t_all is None or t[-1] > t_all[-1]:
            t_all, a0 = t, a[0]
    th, n = theory(t_all, a0)
    ax.semilogy(t_all, th, "k--", label=f"viscous linear theory, n = {n:.3f}")
    ax.axhline(UNTIL, color="grey", lw=0.5)
    ax.text(0.02, UNTIL * 1.05, "end of the fitted range (k a = 0.19)", fontsize=8, color="grey")
    ax.set_xlabel("t sqrt(g/lambda)")
    ax.set_ylabel("amplitude / lambda (interface probe)")
    ax.set_title("Rayleigh-Taylor, k a0 = 0.047, A = 0.286, Re = 420: amplitude against linear theory")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "validation_rayleigh_taylor_linear.png"), dpi=110)


def large(run, out):
    from vtkmodules.vtkIOXML import vtkXMLPolyDataReader
    from vtkmodules.util.numpy_support import vtk_to_numpy
    fig, axes = plt.subplots(1, 3, figsize=(9, 6))
    for ax, t in zip(axes, (1.0, 3.0, 5.0)):
        import re
        steps = re.findall(r'timestep="([^"]+)"[^>]*file="([^"]+)"', open(run + "/particles.pvd").read())
        time, vtm = min(steps, key=lambda e: abs(float(e[0]) - t))
        step = os.path.join(run, vtm)[:-4]
        files = sorted(glob.glob((step or "") + "/*.vtp"))
        for f in files:
            r = vtkXMLPolyDataReader()
            r.SetFileName(f)
            r.Update()
            o = r.GetOutput()
            x = vtk_to_numpy(o.GetPoints().GetData())
            phase = vtk_to_numpy(o.GetPointData().GetArray("phase"))
            fluid = phase < 2
            ax.scatter(x[fluid, 0], x[fluid, 1], c=np.where(phase[fluid] == 1, "tab:red", "tab:blue"), s=1.5, lw=0)
        ax.set_title(f"t = {float(time):.2f}")
        ax.set_aspect("equal")
        ax.set_xlim(0, 1)
        ax.set_ylim(0, 2)
    fig.suptitle("Rayleigh-Taylor (rho 1.8 over 1, Re = 420, dp = 0.02): heavy red, light blue")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "validation_rayleigh_taylor.png"), dpi=110)


def main():
    a = argparse.ArgumentParser()
    a.add_argument("--linear", nargs="*", default=[])
    a.add_argument("--large")
    a.add_argument("--spate", default="build/bin/spate")
    a.add_argument("--out", default="docs/images")
    args = a.parse_args()
    if args.linear:
        linear([tuple(s.split("=", 1)) for s in args.linear], args.spate, args.out)
    if args.large:
        large(args.large, args.out)


if __name__ == "__main__":
    main()
