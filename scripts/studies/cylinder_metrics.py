"""Flow past a cylinder (cases/cylinder_flow_2d.yaml): drag and lift coefficients and the Strouhal
number from a run's probes, as Schafer & Turek (1996) define them for their channel:
c_D = 2 F_D / (rho U^2 D), c_L = 2 F_L / (rho U^2 D), St = D f / U, with U the mean inflow
velocity (2/3 of the parabola's peak) and F the fluid's whole force on the cylinder (pressure and
viscous: the force probe's fx + fx_viscous), plus, where the run has the probe `drive`, the
mean pressure gradient's push on the cylinder that a body-force-driven channel lacks: in the
periodic channel the drive's body force f stands for their pressure drop, and with P = p - rho f x
(their pressure, up to a constant) the divergence theorem gives F_theirs = F_spate + rho f V, V the
cylinder's area (docs/studies/cylinder-flow.md). Used by scripts/studies/cylinder-flow."""
import os

import numpy as np

RHO, D, U = 1000.0, 0.1, 0.2  # the case's density, diameter and bulk velocity Q/H


def buoyancy(out, t):
    """rho f V [N/m] at the times t: the drive's body force (probe `drive`) times the density and
    the cylinder's area; 0 where the run has no such probe."""
    path = f"{out}/probes/drive.csv"
    if not os.path.exists(path):
        return np.zeros_like(t)
    d = np.genfromtxt(path, delimiter=",", names=True)
    return RHO * np.interp(t, d["times"], d["fxms2"]) * np.pi * D * D / 4


def read(out):
    d = np.genfromtxt(f"{out}/probes/drag.csv", delimiter=",", names=True)
    t = d["times"]
    b = buoyancy(out, t)
    fx = d["fxNm"] + d["fx_viscousNm"] + b
    fy = d["fyNm"] + d["fy_viscousNm"]
    q = 0.5 * RHO * U * U * D
    return t, fx / q, fy / q, (d["fxNm"] + b) / q


def mean_drag(out, start, end=np.inf):
    """Mean c_D (and its pressure part) over [start, end]."""
    t, cd, cl, cdp = read(out)
    w = (t >= start) & (t <= end)
    return cd[w].mean(), cdp[w].mean(), cl[w].mean()


def spectral_peak(t, x):
    """The dominant frequency of x(t) (mean removed, Hann window, zero-padded FFT), refined by a
    parabola through the three bins around the peak."""
    dt = np.median(np.diff(t))
    x = (x - x.mean()) * np.hanning(len(x))
    spec = np.abs(np.fft.rfft(x, n=8 * len(x)))
    freq = np.fft.rfftfreq(8 * len(x), dt)
    k = 1 + np.argmax(spec[1:])
    a, b, c = spec[k - 1], spec[k], spec[k + 1]
    shift = 0.5 * (a - c) / (a - 2 * b + c) if a - 2 * b + c != 0 else 0.0
    return (k + shift) * (freq[1] - freq[0])


def strouhal(out, start, end=np.inf):
    """St from the shedding frequency: the dominant frequency of the cross-stream velocity at the
    probe `wake` (3 D behind the cylinder, as a hot wire reads it; the lift carries the same
    frequency under the acoustic noise of weakly-compressible SPH). Also the mean c_D and the lift's
    amplitude after a 0.2 s running mean."""
    w = np.genfromtxt(f"{out}/probes/wake.csv", delimiter=",", names=True)
    m = (w["times"] >= start) & (w["times"] <= end)
    f = spectral_peak(w["times"][m], w["vyms"][m])
    t, cd, cl, _ = read(out)
    m = (t >= start) & (t <= end)
    n = max(1, int(round(0.2 / np.median(np.diff(t)))))
    smooth = np.convolve(cl[m], np.ones(n) / n, mode="valid")
    return f * D / U, f, 0.5 * (smooth.max() - smooth.min()), cd[m].mean()
