#!/usr/bin/env python3
"""Plots of the moving-wall validation (docs/studies/moving-walls.md) from the probe files the
tests write: WaveFlume.* (/tmp/spate-test-wave-flume), Sloshing.* (/tmp/spate-test-sloshing-decay,
/tmp/spate-test-sloshing-forced). Usage: moving_walls_plots.py [scratch folder] [images folder]"""
import csv
import math
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

G = 9.81


def read(path):
    t, v = [], []
    with open(path) as f:
        rows = csv.reader(f)
        next(rows)
        for row in rows:
            t.append(float(row[0]))
            v.append(float(row[2]))
    return t, v


def wavenumber(omega, d):
    k = omega * omega / G
    for _ in range(50):
        th = math.tanh(k * d)
        k -= (G * k * th - omega * omega) / (G * th + G * k * d * (1 - th * th))
    return k


def sloshing_frequency(n, L, d):
    k = n * math.pi / L
    return math.sqrt(G * k * math.tanh(k * d))


def sway_amplitude(A, omega, L, d, xi):
    s = sum(4 * L / (n * math.pi) ** 2 * sloshing_frequency(n, L, d) ** 2 / (sloshing_frequency(n, L, d) ** 2 - omega**2)
            * math.cos(n * math.pi * xi / L) for n in range(1, 2001, 2))
    return abs(A * omega * omega / G * s)


def main():
    scratch = sys.argv[1] if len(sys.argv) > 1 else "/tmp"
    images = sys.argv[2] if len(sys.argv) > 2 else "docs/images"
    # Wave flume: S = 0.04 m, T = 1.2 s, d = 0.4 m.
    omega, d, S = 2 * math.pi / 1.2, 0.4, 0.04
    k = wavenumber(omega, d)
    H = S * 2 * (math.cosh(2 * k * d) - 1) / (math.sinh(2 * k * d) + 2 * k * d)
    fig, ax = plt.subplots(figsize=(9, 3.6))
    for name, x in (("g1", 2.0), ("g2", 3.0)):
        t, v = read(f"{scratch}/spate-test-wave-flume/probes/{name}.csv")
        ax.plot(t, v, lw=0.9, label=f"spate, {name} (x = {x} m)")
    ax.axhspan(d - H / 2, d + H / 2, color="0.85", label=f"Biesel: H = {H:.4f} m about d")
    ax.axvspan(8, 14, color="C2", alpha=0.08, label="test window 8-14 s")
    ax.set(xlabel="t [s]", ylabel="water height [m]", title="Piston wave maker (cases/wave_flume_2d.yaml)")
    ax.legend(fontsize=8, loc="lower left")
    fig.tight_layout()
    fig.savefig(f"{images}/validation_wave_flume.png", dpi=90)

    L, d = 1.0, 0.2
    w1 = sloshing_frequency(1, L, d)
    T1 = 2 * math.pi / w1
    fig, axs = plt.subplots(2, 1, figsize=(9, 6.4))
    t, v = read(f"{scratch}/spate-test-sloshing-decay/probes/wall.csv")
    axs[0].plot(t, v, lw=0.9, label="spate, gauge 'wall' (0.01 m from the left wall)")
    end = 3.5 * T1
    for n in range(0, 5):
        axs[0].axvline(end + n * T1, color="0.6", lw=0.6, ls="--", label="forcing stops + n T_1 (theory)" if n == 0 else None)
    axs[0].set(xlabel="t [s]", ylabel="water height [m]",
               title=f"Sloshing tank forced at omega_1 = {w1:.3f} rad/s for 3.5 periods, then free")
    axs[0].legend(fontsize=8, loc="lower left")
    omega, A = 0.8 * w1, 0.01
    period = 2 * math.pi / omega
    t, v = read(f"{scratch}/spate-test-sloshing-forced/probes/wall.csv")
    axs[1].plot(t, v, lw=0.9, label="spate")
    a = sway_amplitude(A, omega, L, d, 0.01)
    axs[1].axhspan(d - a, d + a, color="0.85", label=f"linear theory: amplitude {a:.4f} m at omega")
    axs[1].axvspan(3 * period, 9 * period, color="C2", alpha=0.08, label="fit window")
    axs[1].set(xlabel="t [s]", ylabel="water height [m]", title="Forced sway A = 0.01 m at 0.8 omega_1")
    axs[1].legend(fontsize=8, loc="lower left")
    fig.tight_layout()
    fig.savefig(f"{images}/validation_sloshing.png", dpi=90)


if __name__ == "__main__":
    main()
