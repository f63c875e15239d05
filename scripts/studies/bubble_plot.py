"""The rising bubble (cases/bubble_rise_2d.yaml) against Hysing et al. (2009), test case 1: rise
velocity and centroid height from the `bubble` probe, the bubble's shape and circularity from the
snapshots. Usage: bubble_plot.py RUN_DIR OUT.png (called by scripts/studies/validation-report)."""
import math
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from run_output import probe_table, saved_steps, snapshot_arrays  # noqa: E402

run, out = Path(sys.argv[1]), Path(sys.argv[2])
DP, H = 0.025, 1.3 * 0.025  # the case's dp and smoothing length
BUBBLE = 1                 # the bubble's phase (second fluid)


def snapshot(step_dir):
    """Positions of the bubble's particles in one saved step (every slab)."""
    pts, a = snapshot_arrays(step_dir, ["phase"])
    return pts[a["phase"] == BUBBLE, :2]


def colour_field(x):
    """c(x) = sum_j dp^2 W(x - x_j) (Wendland C2, 2D) on a grid of spacing dp/4 around the bubble."""
    s = DP / 4
    lo, hi = x.min(0) - 2 * H - 2 * s, x.max(0) + 2 * H + 2 * s
    gx, gy = np.arange(lo[0], hi[0], s), np.arange(lo[1], hi[1], s)
    X, Y = np.meshgrid(gx, gy)
    c = np.zeros_like(X)
    norm = 7 / (4 * math.pi * H * H)
    for p in x:
        q = np.hypot(X - p[0], Y - p[1]) / H
        c += DP * DP * np.where(q < 2, norm * (1 - q / 2) ** 4 * (2 * q + 1), 0)
    return X, Y, c


def circularity(x, ax=None, **style):
    X, Y, c = colour_field(x)
    fig = None
    if ax is None:
        fig, ax = plt.subplots()
    cs = ax.contour(X, Y, c, levels=[0.5], **style)
    perimeter = sum(np.sum(np.hypot(*np.diff(seg, axis=0).T)) for seg in cs.allsegs[0])
    if fig:
        plt.close(fig)
    return 2 * math.sqrt(math.pi * len(x) * DP * DP) / perimeter


p = probe_table(run / "probes" / "bubble.csv")  # time, step, x, y, vx, vy
t, y, vy = p[:, 0], p[:, 3], p[:, 5]
k = int(np.argmax(vy))
y3 = float(np.interp(3.0, t, y))
# The saved steps and their times.
entries = saved_steps(run)
times = np.array([t for t, _ in entries])
steps = [d for _, d in entries]
circ = [circularity(snapshot(d)) for d in steps]

fig, axs = plt.subplots(1, 4, figsize=(15, 4), gridspec_kw={"width_ratios": [1.2, 1.2, 1.2, 0.8]})
ax = axs[0]
ax.plot(t, vy, "k-", label="spate, dp = 1/40")
ax.plot([0.9213], [0.2417], "ro", label="Hysing: max 0.2417 at t = 0.921")
ax.axhspan(0.95 * 0.2417, 1.05 * 0.2417, color="r", alpha=0.1, label="+-5%")
ax.set_xlabel("t")
ax.set_ylabel("rise velocity")
ax.legend(fontsize=8, loc="lower right")
ax.grid(alpha=0.3)
ax = axs[1]
ax.plot(t, y, "k-", label="spate centroid")
ax.plot([3.0], [1.0813], "ro", label="Hysing: 1.0813 at t = 3")
ax.errorbar([3.0], [1.0813], yerr=[0.05 * 1.0813], color="r", capsize=4)
ax.set_xlabel("t")
ax.set_ylabel("centroid height")
ax.legend(fontsize=8)
ax.grid(alpha=0.3)
ax = axs[2]
ax.plot(times, circ, "ko-", label="spate (0.5 contour of the colour)")
ax.plot([1.9], [0.9013], "ro", label="Hysing: min 0.9013 at t = 1.9")
ax.set_ylim(0.8, 1.02)
ax.set_xlabel("t")
ax.set_ylabel("circularity")
ax.legend(fontsize=8)
ax.grid(alpha=0.3)
ax = axs[3]
x0, x3 = snapshot(steps[0]), snapshot(steps[-1])
ax.plot(x0[:, 0], x0[:, 1], ".", color="0.75", ms=2)
ax.plot(x3[:, 0], x3[:, 1], ".", color="C0", ms=2)
circularity(x0, ax, colors="0.5", linewidths=0.8)
c_end = circularity(x3, ax, colors="k", linewidths=1.2)
ax.set_xlim(0, 1)
ax.set_ylim(0, 2)
ax.set_aspect("equal")
ax.set_title(f"t = 0 (grey), t = {times[-1]:.1f}", fontsize=9)
fig.tight_layout()
fig.savefig(out, dpi=110)
print(f"bubble rise: max rise velocity {vy[k]:.4f} at t = {t[k]:.3f} (Hysing 0.2417 at 0.9213, "
      f"{100 * (vy[k] / 0.2417 - 1):+.1f}%), centroid at t = 3 {y3:.4f} (1.0813, {100 * (y3 / 1.0813 - 1):+.1f}%), "
      f"circularity at t = {times[-1]:.1f} {c_end:.3f}, minimum {min(circ):.3f}")
