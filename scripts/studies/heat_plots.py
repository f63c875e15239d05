#!/usr/bin/env /usr/bin/python3
"""Figures of the heat-transfer validation (docs/validation.md, docs/studies/heated-cavity.md):
the two-material slab's steady profile beside the exact one; the heated cavity's isotherms and
streamlines with its Nusselt-number history; the Poiseuille channel with a temperature-dependent
viscosity against its exact profile; the cavity's Nusselt number at Ra = 1e5 at several resolutions.
Reads the final checkpoint and the probes of runs of cases/conduction_2d.yaml,
cases/heated_cavity_2d.yaml and cases/poiseuille_thermal_2d.yaml (e.g. the folders the validation
tests leave in /tmp/spate-test-*-heat-slab, -heat-cavity-2.6295e-3, -heat-poiseuille).
Usage: scripts/studies/heat_plots.py [--slab RUN] [--cavity RUN] [--poiseuille RUN]
                                     [--ra1e5 RUN ...] [--out DIR (default docs/images)]"""
import argparse
import glob
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


def poiseuille(run, out):
    """Velocity across the channel against the exact profile u(y) = int_0^y rho F (y* - s) / mu(s) ds."""
    p = particles(run)
    fl = p["material"] == 0
    L, F, rho = 1e-3, 2e-4, 1000.0
    table_T, table_mu = [290, 300, 310], [2e-3, 1e-3, 0.5e-3]
    y = np.linspace(0, L, 20001)
    mu = np.interp(290 + 20 * y / L, table_T, table_mu)
    y_star = np.trapz(y / mu, y) / np.trapz(1 / mu, y)
    g = rho * F * (y_star - y) / mu
    u = np.concatenate([[0], np.cumsum(0.5 * (g[1:] + g[:-1]) * np.diff(y))])
    u_const = rho * F / (2 * 1e-3) * y * (L - y)
    fig, ax = plt.subplots(figsize=(6, 3.8))
    ax.plot(y / L, u * 1e6, "k-", lw=1, label="exact, mu(T) from the table")
    ax.plot(y / L, u_const * 1e6, "k:", lw=1, label="exact, constant mu = 1 mPa s (300 K)")
    ax.plot(p["y"][fl] / L, p["vx"][fl] * 1e6, "o", ms=2.5, color="tab:red", label="spate, every particle")
    ax.set_xlabel("y / L  (floor 290 K, lid 310 K)")
    ax.set_ylabel("u [µm/s]")
    ax.set_title("cases/poiseuille_thermal_2d.yaml: steady profile at t = 1 s")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out + "/heat_poiseuille_viscosity.png", dpi=120)


def ra1e5(runs, out):
    """nu_hot against time at Ra = 1e5 for runs at several resolutions (their dp from case.yaml)."""
    fig, ax = plt.subplots(figsize=(6.4, 3.8))
    for run in runs:
        dp = float([l.split(":")[1] for l in open(run + "/case.yaml") if l.startswith("dp:")][0])
        d = np.loadtxt(run + "/probes/nu_hot.csv", delimiter=",", skiprows=1)
        ax.plot(d[:, 0], d[:, 3], lw=0.8, label="L/%d" % round(0.05 / dp))
    ax.axhline(4.519, color="k", lw=1, ls="--", label="de Vahl Davis 4.519")
    ax.axhspan(4.519 * 0.9, 4.519 * 1.1, color="0.9", label="±10%")
    ax.set_ylim(3, 7)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("nu_hot")
    ax.set_title("heated cavity, Ra = 1e5")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out + "/heat_cavity_ra1e5.png", dpi=120)


if __name__ == "__main__":
    a = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    a.add_argument("--slab")
    a.add_argument("--cavity")
    a.add_argument("--poiseuille")
    a.add_argument("--ra1e5", nargs="+")
    a.add_argument("--out", default="docs/images")
    args = a.parse_args()
    if args.slab:
        slab(args.slab, args.out)
    if args.cavity:
        cavity(args.cavity, args.out)
    if args.poiseuille:
        poiseuille(args.poiseuille, args.out)
    if args.ra1e5:
        ra1e5(args.ra1e5, args.out)
