"""The impact-pressure figure of docs/studies/impact-pressures.md: each run's sensors against the experiment, both
through the same trailing moving average, and the metrics of each (scripts/studies/impact_metrics.py).
Used by scripts/studies/validation_plots.py (the schemes) and scripts/studies/impact-study (resolution, sound
speed, shifting); as a program:
    impact_plot.py CASE OUT.png DATA_DIR RUN_DIR=LABEL [RUN_DIR=LABEL ...]"""
import math
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

sys.path.insert(0, str(Path(__file__).parent))
import impact_metrics as im  # noqa: E402

G = 9.81


def impact_figure(case, runs, data_dir, out, window_s=None):
    """runs: [(run folder, label)] (missing folders are skipped). Writes `out`, prints each run's
    metrics against the experiment's and returns them as {label: [(probe, exp, spate)]}."""
    spec = im.CASES[case]
    H = spec["H"]
    if window_s is None:
        window_s = im.WINDOW_TAU * math.sqrt(H / G)
    w = window_s * math.sqrt(G / H)
    runs = [(Path(r), label) for r, label in runs if Path(r).exists()]
    n = len(spec["sensors"])
    fig, axs = plt.subplots(n, 1, figsize=(7.5, 2.7 * n + 0.4), squeeze=False)
    shift = im.experiment_shift(case, data_dir)
    clock = f", experiment {shift:+.3f} tau (level clock)" if shift else ""
    for ax, (probe, name) in zip(axs[:, 0], spec["sensors"]):
        raw = im.read_experiment(Path(data_dir) / name, shift)
        avg = im.moving_average(raw, w)
        ax.plot([t for t, _ in raw], [p for _, p in raw], ".", color="0.6", ms=2, label="experiment")
        ax.plot([t for t, _ in avg], [p for _, p in avg], "k-", lw=1.2, label=f"experiment, {1e3 * window_s:.0f} ms mean")
        for run, label in runs:
            rec = im.moving_average(im.read_sensor(run, probe, H), w)
            ax.plot([t for t, _ in rec], [p for _, p in rec], "-", lw=0.9, label=label)
        ax.axhline(0, color="k", lw=0.5)
        ax.set_xlim(2, 6.5)
        ax.set_ylim(-1, 4.5)
        ax.set_title(f"{case}: sensor {probe}, {1e3 * window_s:.0f} ms mean{clock}", fontsize=9)
        ax.set_ylabel("p / (rho g H)")
        ax.grid(alpha=0.3)
    axs[-1, 0].set_xlabel("tau = t sqrt(g/H)")
    axs[0, 0].legend(fontsize=7, loc="upper right")
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)
    results = {}
    for run, label in runs:
        results[label] = im.compare(run, case, data_dir, window_s)
        for probe, e, m in results[label]:
            print(f"{case} {probe} {label}: arrival {m['arrival']:.3f} ({1e3 * (m['arrival'] - e['arrival']) / math.sqrt(G / H):+.1f} ms), "
                  f"peak {m['peak']:.3f} ({100 * (m['peak'] / e['peak'] - 1):+.0f}%), plateau {m['plateau']:.3f} "
                  f"({100 * (m['plateau'] / e['plateau'] - 1):+.1f}%), lowest after arrival {m['lowest']:+.3f}")
    return results


if __name__ == "__main__":
    case, out, data_dir = sys.argv[1:4]
    impact_figure(case, [tuple(a.split("=", 1)) for a in sys.argv[4:]], data_dir, out)
