"""The pressure along the end wall of the Lobovsky tank over the plateau window, and the flow that
sets it (docs/studies/impact-pressures.md, "What keeps p3 low: a vortex in the corner"). The runs are of a
Lobovsky case with extra probes every 5 mm up the end wall (scripts/studies/impact-study writes them):
wall-pressure sensors `wZZZ` (4.2 mm across, as p1-p4) and velocity probes `vZZZ` 1 cm off the wall,
ZZZ the height in mm. Each run's window is the issue's plateau window of its own p1: 1 <= tau -
arrival <= 2; the experiment's sensors are averaged over the same window after its own p1 arrival,
so that the two clocks of the records do not matter. Prints the profiles; with --flow RUN@T the
figure adds the particles near the corner of RUN at the snapshot nearest T seconds.
    impact_profile.py OUT.png RUN_DIR=LABEL [RUN_DIR=LABEL ...] [--flow RUN_DIR@T ...]"""
import math
import re
import sys
from pathlib import Path

import matplotlib
import numpy as np
import yaml

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

sys.path.insert(0, str(Path(__file__).parent))
import impact_metrics as im  # noqa: E402
from run_output import probe_table, saved_step_near, snapshot_arrays  # noqa: E402

H = 0.3
G = 9.81
RHO = 1000.0
DATA = Path(__file__).resolve().parents[2] / "tests" / "validation_data"
EXPERIMENT = (("p1", 3), ("p3", 30), ("p4", 80))


def window_mean(record, lo, hi):
    a = np.array(record)
    m = (a[:, 0] >= lo) & (a[:, 0] <= hi)
    return float(a[m, 1].mean()) if m.any() else math.nan


def p1_arrival(record):
    return im.impact(im.moving_average(record, im.WINDOW_TAU))["arrival"]


def run_profile(run):
    """(heights [mm], P over the window, vy 1 cm off the wall over the window [m/s], window)."""
    heights = sorted(int(m.group(1)) for f in (Path(run) / "probes").glob("w*.csv") if (m := re.fullmatch(r"w(\d+)\.csv", f.name)))
    arrival = p1_arrival(im.read_sensor(run, "p1", H))
    lo, hi = arrival + 1, arrival + 2
    P = [window_mean(im.read_sensor(run, f"w{z:03d}", H), lo, hi) for z in heights]
    vy = []
    scale = math.sqrt(G / H)
    for z in heights:
        rows = probe_table(Path(run) / "probes" / f"v{z:03d}.csv")
        vy.append(window_mean(list(zip(rows[:, 0] * scale, rows[:, 3])), lo, hi))
    return heights, P, vy, (lo, hi)


def experiment_profile():
    arrival = p1_arrival(im.read_experiment(DATA / "lobovsky_2014_p1.csv"))
    out = []
    for name, z in EXPERIMENT:
        rec = im.read_experiment(DATA / f"lobovsky_2014_{name}.csv")
        out.append((z, window_mean(rec, arrival + 1, arrival + 2)))
    return out


def fluid_snapshot(run, t):
    """(time, positions, velocities, pressures, densities) of the fluid particles (2D) at the
    saved step nearest t."""
    time, step_dir = saved_step_near(Path(run), t)
    x, a = snapshot_arrays(step_dir, ["velocity", "pressure", "density", "kind"])
    fluid = a["kind"] == 0
    return time, x[fluid, :2], a["velocity"][fluid, :2], a["pressure"][fluid], a["density"][fluid]


def corner_circulation(run, t, dp, ratio=1.3):
    """The circulation [m^2/s] of the fluid in the corner, x > 1.5 m and z < 0.08 m: the sum of
    V_i omega_i, omega_i = -sum_j V_j (v_j - v_i) x grad_i W_ij (Wendland C2, 2D, h = ratio dp; fluid
    neighbours only). Negative: turning as the eddy does, down the wall and back along the floor."""
    from scipy.spatial import cKDTree

    time, x, v, _, rho = fluid_snapshot(run, t)
    h = ratio * dp
    norm = 7.0 / (4.0 * math.pi * h * h)
    volume = RHO * dp * dp / rho
    i, j = cKDTree(x).query_pairs(2 * h, output_type="ndarray").T
    r = x[i] - x[j]
    q = np.linalg.norm(r, axis=1) / h
    grad = (norm * -5.0 * (1 - q / 2) ** 3 / (h * h))[:, None] * r  # grad_i W_ij, dW/dr / r times r_ij
    dv = v[j] - v[i]
    cross = dv[:, 0] * grad[:, 1] - dv[:, 1] * grad[:, 0]
    omega = np.zeros(len(x))
    np.add.at(omega, i, -volume[j] * cross)
    np.add.at(omega, j, -volume[i] * cross)  # (v_i - v_j) x grad_j W_ji: the same product
    box = (x[:, 0] > 1.5) & (x[:, 1] < 0.08)
    return time, float(np.sum(omega[box] * volume[box]))


def bottom_layer(run, t, x0=1.3):
    """The mean horizontal velocity of the fluid within 1 cm of x0, in the bottom 5 mm and at
    20-35 mm over the floor: how much the surge's bottom layer lags the stream above it."""
    time, x, v, _, _ = fluid_snapshot(run, t)
    near = np.abs(x[:, 0] - x0) < 0.01
    low = near & (x[:, 1] < 0.005)
    mid = near & (x[:, 1] >= 0.020) & (x[:, 1] < 0.035)
    return time, float(v[low, 0].mean()), float(v[mid, 0].mean())


def flow_panel(ax, run, t, first):
    time, x, v, p, _ = fluid_snapshot(run, t)
    m = (x[:, 0] > 1.49) & (x[:, 1] < 0.14)
    sc = ax.scatter(x[m, 0], x[m, 1], c=p[m] / (RHO * G * H), s=4, cmap="viridis", vmin=0, vmax=1)
    q = m & (np.arange(len(x)) % max(1, int(m.sum() // 900)) == 0)
    ax.quiver(x[q, 0], x[q, 1], v[q, 0], v[q, 1], scale=20, width=0.003)
    for _, z in EXPERIMENT:
        ax.plot([1.61], [z / 1000], "r>", ms=7)
    ax.set_xlim(1.49, 1.615)
    ax.set_ylim(0, 0.14)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    if first:
        ax.set_ylabel("z [m]")
    ax.set_title(f"{Path(run).name}\nt = {time:.2f} s: p / (rho g H) and velocity", fontsize=9)
    return sc


def main(argv):
    out = argv[0]
    runs, flows = [], []
    args = iter(argv[1:])
    for a in args:
        if a == "--flow":
            run, t = next(args).rsplit("@", 1)
            flows.append((run, float(t)))
        else:
            run, label = a.split("=", 1)
            runs.append((run, label))
    fig, axes = plt.subplots(1, 2 + len(flows), figsize=(5 * (2 + len(flows)), 5.5))
    for run, label in runs:
        z, P, vy, (lo, hi) = run_profile(run)
        axes[0].plot(P, z, "-", label=label)
        axes[1].plot(vy, z, "-", label=label)
        print(f"{label}: window tau {lo:.3f}-{hi:.3f}")
        for zz, pp, vv in zip(z, P, vy):
            print(f"  z = {zz:3d} mm  P = {pp:.3f}  vy(1 cm off the wall) = {vv:+.3f} m/s")
        dp = float(yaml.safe_load((Path(run) / "case.yaml").read_text())["dp"])
        t, low, mid = bottom_layer(run, 0.45)
        print(f"  t = {t:.2f} s, x = 1.3 m: u = {low:.3f} m/s in the bottom 5 mm, {mid:.3f} m/s at 20-35 mm")
        for t in (0.6, 0.7, 0.8):
            t, circulation = corner_circulation(run, t, dp)
            print(f"  t = {t:.2f} s: circulation in the corner (x > 1.5 m, z < 0.08 m) {circulation:+.3f} m^2/s")
    exp = experiment_profile()
    axes[0].plot([p for _, p in exp], [z for z, _ in exp], "ko", label="experiment (p1, p3, p4)")
    print("experiment: " + ", ".join(f"z = {z} mm P = {p:.3f}" for z, p in exp))
    axes[0].set_xlabel("p / (rho g H), mean over 1 <= tau - arrival(p1) <= 2")
    axes[1].set_xlabel("vertical velocity 1 cm off the wall [m/s], same window")
    for ax, where in zip(axes[:2], ("upper right", "upper left")):
        ax.set_ylabel("height on the end wall [mm]")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc=where)
    axes[1].axvline(0, color="k", lw=0.5)
    for k, (ax, (run, t)) in enumerate(zip(axes[2:], flows)):
        sc = flow_panel(ax, run, t, k == 0)
    if flows:
        fig.colorbar(sc, ax=axes[2:].tolist(), shrink=0.8)
    fig.savefig(out, dpi=90, bbox_inches="tight")


if __name__ == "__main__":
    main(sys.argv[1:])
