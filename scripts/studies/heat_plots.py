#!/usr/bin/env /usr/bin/python3
"""Figures of the heat-transfer validation (docs/validation.md, docs/studies/heated-cavity.md):
the two-material slab's steady profile beside the exact one, and the heated cavity's isotherms and
streamlines with its Nusselt-number history. Reads the final checkpoint and the probes of runs of
cases/conduction_2d.yaml and cases/heated_cavity_2d.yaml (e.g. the folders the validation tests leave
in /tmp/spate-test-*-heat-slab and -heat-cavity-2.6295e-3).
Usage: scripts/studies/heat_plots.py SLAB_RUN CAVITY_RUN [OUT_DIR (default docs/images)]"""
import glob
import sys

import h5py
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import matplotlib.tri as mtri
import numpy as np


def particles(run):
    f = sorted(glob.glob(run + "/checkpoints/*.h5"))[-1]
    p = h5py.File(f, "r")["particles"]
    return {k: p[k][:] for k in ("x", "y", "vx", "vy", "temperature", "material")}


def slab(run, out):
    p = particles(run)
    inside = (p["x"] > 0) & (p["x"] < 0.1) & (p["y"] > 0) & (p["y"] < 0.05)
    q = 20 / (0.05 / 10 + 0.05 / 1)
    xs = np.linspace(0, 0.1, 201)
    exact = np.where(xs < 0.05, 310 - q * xs / 10, 310 - q * 0.005 - q * (xs - 0.05))
    fig, ax = plt.subplots(figsize=(6, 3.6))
    ax.plot(xs * 1e3, exact, "k-", lw=1, label="exact")
    ax.plot(p["x"][inside] * 1e3, p["temperature"][inside], "o", ms=2, color="tab:red", label="spate, every particle")
    ax.axvline(50, color="0.6", lw=0.8)
    ax.set_xlabel("x [mm]  (liner k = 10 | fluid k = 1 W/(m K))")
    ax.set_ylabel("T [K]")
    ax.set_title("cases/conduction_2d.yaml: steady profile")
    ax.legend()
    fig.tight_layout()
    fig.savefig(out + "/heat_conduction_profile.png", dpi=120)


def cavity(run, out):
    p = particles(run)
    fl = p["material"] == 0
    L = 0.05
    x, y, T = p["x"][fl] / L, p["y"][fl] / L, (p["temperature"][fl] - 292.65) / 1.0
    fig, axes = plt.subplots(1, 2, figsize=(10, 4.4))
    ax = axes[0]
    tri = mtri.Triangulation(x, y)
    cs = ax.tricontour(tri, T, levels=np.linspace(0.05, 0.95, 10), colors="tab:red", linewidths=0.8)
    ax.clabel(cs, fmt="%.1f", fontsize=7)
    gx, gy = np.meshgrid(np.linspace(0.01, 0.99, 60), np.linspace(0.01, 0.99, 60))
    u = mtri.LinearTriInterpolator(tri, p["vx"][fl])(gx, gy)
    v = mtri.LinearTriInterpolator(tri, p["vy"][fl])(gx, gy)
    ax.streamplot(gx, gy, np.ma.filled(u, 0), np.ma.filled(v, 0), color="tab:blue", density=0.9, linewidth=0.6)
    ax.set_aspect("equal")
    ax.set_xlim(0, 1), ax.set_ylim(0, 1)
    ax.set_title("Ra = 1e4: isotherms (T - T_c)/dT, streamlines")
    ax = axes[1]
    for name, style in (("nu_hot", "tab:red"), ("nu_cold", "tab:blue")):
        d = np.loadtxt(run + "/probes/%s.csv" % name, delimiter=",", skiprows=1)
        ax.plot(d[:, 0], d[:, 3], color=style, lw=0.8, label=name)
    ax.axhline(2.243, color="k", lw=1, ls="--", label="de Vahl Davis 2.243")
    ax.set_ylim(1.5, 3.5)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("mean Nusselt number")
    ax.legend()
    fig.tight_layout()
    fig.savefig(out + "/heat_cavity_ra1e4.png", dpi=120)


if __name__ == "__main__":
    out = sys.argv[3] if len(sys.argv) > 3 else "docs/images"
    slab(sys.argv[1], out)
    cavity(sys.argv[2], out)
