"""What the flow does at the end wall of the Lobovsky tank while the pressure above the floor builds
(docs/studies/impact-pressures.md, "Why the pressure above the floor builds late"): the surge's depth against
Ritter's ideal dam-break solution, printed, and the fluid's pressure and velocity near the wall at a
few times, drawn; the corner below the stream while the plateau builds, averaged, printed. From a
run with snapshots:
    spate run cases/dam_break_lobovsky.yaml --set dp=0.0025 --set time.end=0.7 --set output.interval=0.01 --out RUN
    impact_runup.py RUN OUT.png"""
import sys
from pathlib import Path

import matplotlib
import numpy as np
import yaml

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from run_output import saved_step_near, saved_steps, snapshot_arrays  # noqa: E402

G, H, RHO = 9.81, 0.3, 1000.0
DAM = 0.6  # the column's length: the dam's position [m]
SENSORS = [(0.003, "p1"), (0.03, "p3"), (0.08, "p4")]


def fluid_of(step_dir):
    """(positions, pressures, velocities) of the fluid in a saved step, and the end wall's x (the
    outermost wall particle)."""
    x, a = snapshot_arrays(step_dir, ["pressure", "velocity", "kind"])
    fluid = a["kind"] == 0
    return x[fluid], a["pressure"][fluid], a["velocity"][fluid], x[~fluid, 0].max()


def fluid_at(run, want):
    """The time of the saved step nearest `want`, and fluid_of that step."""
    t, step_dir = saved_step_near(run, want)
    return (t, *fluid_of(step_dir))


def ritter_depth(x, t):
    """Ritter's (1892) depth of an ideal dam break over a dry bed, column height H at x < DAM."""
    c = (G * H) ** 0.5
    xi = (x - DAM) / t
    return (2 * c - xi) ** 2 / (9 * G) if -c <= xi <= 2 * c else 0.0


def corner_profile(run, t0=0.60, t1=0.70, strip=0.02):
    """The end-wall corner while the plateau builds (docs/studies/impact-pressures.md, the gate section's
    plateaus): over the saved steps with t0 <= t <= t1, the mean pressure and vertical velocity of
    the fluid within `strip` of the end wall, and the mean horizontal velocity 4-6 cm before it,
    in 1 cm bands of height up to 8 cm; printed."""
    tank = yaml.safe_load((run / "case.yaml").read_text())["tank"]
    face = float(tank["origin"][0]) + float(tank["size"][0])  # the end wall's inner face
    bands = np.arange(0.0, 0.09, 0.01)
    p_sum, v_sum, u_sum, n = np.zeros(len(bands)), np.zeros(len(bands)), np.zeros(len(bands)), 0
    for t, step_dir in saved_steps(run):
        if not t0 - 1e-6 <= t <= t1 + 1e-6:
            continue
        x, p, v, _ = fluid_of(step_dir)
        for k, z in enumerate(bands):
            band = (x[:, 1] >= z) & (x[:, 1] < z + 0.01)
            at_wall, before = band & (x[:, 0] >= face - strip), band & (np.abs(x[:, 0] - (face - 0.05)) < 0.01)
            p_sum[k] += p[at_wall].mean() / (RHO * G * H) if at_wall.any() else np.nan
            v_sum[k] += v[at_wall, 1].mean() if at_wall.any() else np.nan
            u_sum[k] += v[before, 0].mean() if before.any() else np.nan
        n += 1
    print(f"the corner, mean of {n} saved steps in {t0} <= t <= {t1} s: height: p/(rho g H) within {100 * strip:.0f} cm "
          "of the wall (v there; u 4-6 cm before it) [m/s]")
    print("  " + "  ".join(f"{100 * z:.0f} cm: {p_sum[k] / n:.2f} (v {v_sum[k] / n:+.2f}, u {u_sum[k] / n:+.2f})"
                           for k, z in enumerate(bands)))


def main(run, out):
    dp = float(yaml.safe_load((run / "case.yaml").read_text())["dp"])  # the run's effective case
    for want in (0.3, 0.4, 0.45):
        t, x, _, _, _ = fluid_at(run, want)
        cells = []
        for at in (0.8, 1.0, 1.2, 1.4):
            column = x[np.abs(x[:, 0] - at) < dp]
            depth = column[:, 1].max() + dp / 2 if len(column) else 0.0  # the surface half a dp above the top particle
            cells.append(f"x = {at} m: {100 * depth:.1f} cm (Ritter {100 * ritter_depth(at, t):.1f})")
        print(f"t = {t:.3f} s, front at x = {x[:, 0].max():.3f} m | " + " | ".join(cells))
    corner_profile(run)
    times = (0.47, 0.50, 0.53, 0.62)
    fig, axes = plt.subplots(1, len(times), figsize=(3.0 * len(times) + 1, 4.4), sharey=True)
    tau = (G / H) ** 0.5
    for ax, want in zip(axes, times):
        t, x, p, v, wall = fluid_at(run, want)
        near = (x[:, 0] > wall - 0.2) & (x[:, 1] < 0.3)
        sc = ax.scatter(x[near, 0], x[near, 1], c=p[near] / (RHO * G * H), s=1.2, cmap="viridis", vmin=0, vmax=1.2)
        arrows = near & (np.arange(len(x)) % 9 == 0)
        ax.quiver(x[arrows, 0], x[arrows, 1], v[arrows, 0], v[arrows, 1], scale=40, width=0.004, color="k", alpha=0.5)
        for z, name in SENSORS:
            ax.plot([wall - 0.008, wall], [z, z], "r-", lw=2)
            ax.text(wall - 0.012, z, name, color="r", fontsize=7, va="center", ha="right")
        ax.set_title(f"t = {t:.2f} s, tau = {t * tau:.2f}", fontsize=9)
        ax.set_aspect("equal")
        ax.set_xlim(wall - 0.2, wall + 0.004)
        ax.set_ylim(0, 0.3)
        ax.set_xlabel("x [m]")
    axes[0].set_ylabel("z [m]")
    fig.colorbar(sc, ax=list(axes), label="p / (rho g H)", shrink=0.85)
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    main(Path(sys.argv[1]), sys.argv[2])
