"""The dam break with air (cases/dam_break_air_2d.yaml) against the single-phase dam break
(cases/dam_break_2d.yaml): the pressure field of the water and of the air at T = t sqrt(2g/a) = 1
and 2, and the water's front. Usage: air_dam_plot.py AIR_RUN SINGLE_RUN OUT.png (called by
scripts/studies/validation-report; both runs with snapshots at T = 1 and 2)."""
import math
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from run_output import probe_table, saved_step_near, snapshot_arrays  # noqa: E402

air_run, single_run, out = Path(sys.argv[1]), Path(sys.argv[2]), Path(sys.argv[3])
A, H, G = 0.0572, 0.1144, 9.81  # column width and height, gravity (the cases')
T_OF_T = math.sqrt(2 * G / A)
RHO_G_H = 1000 * G * H


def snapshot(step_dir):
    """Positions, pressures and phases of the fluid particles of one saved step (every slab)."""
    pts, a = snapshot_arrays(step_dir, ["pressure", "phase", "kind"])
    phase = a["phase"] if a["phase"] is not None else np.where(a["kind"] == 0, 0, -1)
    s = np.c_[pts[:, :2], a["pressure"], phase]
    return s[s[:, 3] >= 0]


def snapshot_at(run, T):
    """The saved step nearest to T."""
    t, step_dir = saved_step_near(run, T / T_OF_T)
    return t, snapshot(step_dir)


fig, axes = plt.subplots(3, 2, figsize=(12, 10), gridspec_kw={"height_ratios": [1, 1, 1.1]})
for col, T in enumerate((1.0, 2.0)):
    for row, (run, title) in enumerate(((single_run, "single phase"), (air_run, "with air"))):
        t, s = snapshot_at(run, T)
        ax = axes[row, col]
        water, air = s[s[:, 3] == 0], s[s[:, 3] == 1]
        if len(air):
            ax.scatter(air[:, 0], air[:, 1], c=air[:, 2], s=0.3, cmap="Greys", vmin=0, vmax=30, rasterized=True)
        sc = ax.scatter(water[:, 0], water[:, 1], c=water[:, 2] / RHO_G_H, s=0.6, cmap="viridis", vmin=-0.2, vmax=1.0, rasterized=True)
        ax.set_aspect("equal")
        ax.set_xlim(0, 0.25)
        ax.set_ylim(0, 0.13)
        ax.set_title(f"{title}, T = {t * T_OF_T:.2f}: water p / (rho_w g H) in [{water[:, 2].min() / RHO_G_H:.2f}, "
                     f"{water[:, 2].max() / RHO_G_H:.2f}]" + (f", air p in [{air[:, 2].min():.0f}, {air[:, 2].max():.0f}] Pa" if len(air) else ""),
                     fontsize=8)
        fig.colorbar(sc, ax=ax, shrink=0.7, label="water p / (rho_w g H)")
gs = axes[2, 0].get_gridspec()
for ax in axes[2, :]:
    ax.remove()
ax = fig.add_subplot(gs[2, :])
for run, label in ((single_run, "single phase (dam_break_2d)"), (air_run, "with air (dam_break_air_2d)")):
    f = probe_table(run / "probes" / "front.csv")
    ax.plot(f[:, 0] * T_OF_T, f[:, 2] / A, label=label)
ax.set_xlabel("T = t sqrt(2g/a)")
ax.set_ylabel("water front x / a")
ax.grid(alpha=0.3)
ax.legend()
fig.tight_layout()
fig.savefig(out, dpi=110)
print(f"wrote {out}")
