#!/usr/bin/python3
"""Figure of the tanks of any shape (docs/validation.md, "Tanks of any shape"): the wall gauge of
the half-full circular canal (cases/sloshing_circular_2d.yaml) and of the upright vessel from a mesh
(cases/sloshing_vessel_3d.yaml), forced for three periods and then free, beside a sinusoid at the
linear theory's first frequency (amplitude and phase fitted to the free part; the frequency is
theory's, not fitted).

Usage: shaped_tank_plots.py CANAL_RUN [CANAL_RUN_HALF_DP] VESSEL_RUN OUT.png
where each run is the output folder of `spate run` of the case (`--set dp=0.005` for the half dp)."""
import math
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

G = 9.81


def canal_omega(radius=0.2):
    return math.sqrt(1.3557 * G / radius)  # McIver (1989); scripts/studies/circular_canal_modes.py


def vessel_omega(radius=0.15, depth=0.15, xi=1.8412):
    return math.sqrt(G * xi / radius * math.tanh(xi * depth / radius))


def gauge(run):
    d = np.loadtxt(run + "/probes/wall.csv", delimiter=",", skiprows=1)
    return d[:, 0], d[:, 2]


def free_frequency(t, h, start):
    """Mean angular frequency of the zero up-crossings after `start` (as the tests count them)."""
    m = t > start
    tt, hh = t[m], h[m] - h[m].mean()
    c = [tt[i] - hh[i] * (tt[i + 1] - tt[i]) / (hh[i + 1] - hh[i]) for i in range(len(hh) - 1) if hh[i] < 0 <= hh[i + 1]]
    return 2 * math.pi * (len(c) - 1) / (c[-1] - c[0]), m


def panel(ax, runs, omega, title):
    period = 2 * math.pi / omega
    for k, (run, label) in enumerate(runs):
        t, h = gauge(run)
        measured, free = free_frequency(t, h, 3.25 * period)
        ax.plot(t, 1000 * (h - h[free].mean()), lw=1.2, label="%s: omega %.3f rad/s (%+.2f%%)" % (label, measured, 100 * (measured / omega - 1)))
        if k == 0:
            tf = t[free]
            basis = np.c_[np.cos(omega * tf), np.sin(omega * tf), np.ones_like(tf)]
            coef, *_ = np.linalg.lstsq(basis, h[free], rcond=None)
            ax.plot(tf, 1000 * (basis[:, :2] @ coef[:2]), "k--", lw=1, label="linear theory: omega_1 = %.3f rad/s" % omega)
    ax.axvline(3 * period, color="grey", lw=0.8, ls=":")
    ax.text(3 * period, ax.get_ylim()[1] * 0.9, " the tank stops", color="grey", fontsize=8)
    ax.set_title(title, fontsize=10)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("surface at the wall gauge [mm]")
    ax.legend(fontsize=8, loc="lower left")


def main(argv):
    if len(argv) not in (4, 5):
        print(__doc__)
        return 2
    canal = [(argv[1], "dp = R/20")] + ([(argv[2], "dp = R/40")] if len(argv) == 5 else [])
    vessel, out = argv[-2], argv[-1]
    fig, axes = plt.subplots(2, 1, figsize=(9, 7.5))
    panel(axes[0], canal, canal_omega(), "half-full circular canal, R = 0.2 m (tank: {disc}), omega_1^2 R/g = 1.3557")
    panel(axes[1], [(vessel, "dp = R/10")], vessel_omega(), "upright vessel from an STL, R = h = 0.15 m, omega_1^2 = (g xi/R) tanh(xi h/R)")
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    print("wrote", out)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
