"""The water levels of the Lobovsky dam break against the experiment's gauges H1-H4
(docs/studies/impact-pressures.md, "The release: a lifted gate, and the experiment's two clocks"):
each run's height probes h1-h4 (cases/dam_break_lobovsky*.yaml) over tau = t sqrt(g/H), with
Ritter's ideal dam break, and the time the surge first reads 0.02 H at H2-H4 against the records'
first readings (tests/validation_data/lobovsky_2014_levels.csv).
The records themselves (the paper's Fig. 16, files Fig16_WaterLevels_H<k>_<n>.dat: tau and h/H)
are not shipped with spate; with LEVELS_DIR '-' the figure leaves them out. Usage:
    impact_levels.py OUT.png LEVELS_DIR RUN_DIR=LABEL [RUN_DIR=LABEL ...]"""
import math
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

sys.path.insert(0, str(Path(__file__).parent))
import impact_metrics as im  # noqa: E402
from impact_runup import DAM, G, H, ritter_depth  # noqa: E402
from run_output import probe_table  # noqa: E402

GAUGES = [("h1", 0.3)] + [(name, x) for name, (x, _) in im.LOBOVSKY_GAUGES.items()]


def first_reading(run, gauge, level=0.02):
    """tau at which the gauge first reads `level` H (nan if never)."""
    table = probe_table(Path(run) / "probes" / f"{gauge}.csv")
    scale = math.sqrt(G / H)
    return next((t * scale for t, _, h in table[:, :3] if h / H > level), math.nan)


def main(out, levels_dir, runs):
    runs = [(Path(r), label) for r, label in runs]
    fig, axs = plt.subplots(len(GAUGES), 1, figsize=(7.5, 9.5), sharex=True)
    scale = math.sqrt(G / H)
    for ax, (gauge, x) in zip(axs, GAUGES):
        if levels_dir != "-":
            for f in sorted(Path(levels_dir).glob(f"Fig16_WaterLevels_H{gauge[1]}_*.dat")):
                rows = [line.split() for line in open(f) if line.strip() and not line.startswith("#")]
                ax.plot([float(r[0]) for r in rows], [float(r[1]) for r in rows], "k-", lw=1.0,
                        label="experiment" if "experiment" not in ax.get_legend_handles_labels()[1] else None)
        if x > DAM:  # in the reservoir Ritter's solution holds only until the wave returns from its end
            taus = [0.02 * k for k in range(1, 301)]
            ax.plot(taus, [ritter_depth(x, t / scale) / H for t in taus], "k:", lw=0.9, label="Ritter (ideal)")
        for run, label in runs:
            table = probe_table(run / "probes" / f"{gauge}.csv")
            ax.plot(table[:, 0] * scale, table[:, 2] / H, lw=1.0, label=label)
        ax.set_title(f"water level at x = {x} m ({gauge.upper()})", fontsize=9)
        ax.set_ylabel("h / H")
        ax.set_ylim(0, 1.05 if gauge == "h1" else 0.6)
        ax.grid(alpha=0.3)
    axs[-1].set_xlim(0, 6)
    axs[-1].set_xlabel("tau = t sqrt(g/H)")
    axs[-1].legend(fontsize=7, loc="upper left")  # the panel's dry first two tau
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)
    for run, label in runs:
        cells = []
        for gauge in im.LOBOVSKY_GAUGES:
            first = first_reading(run, gauge)
            cells.append(f"{gauge.upper()} {first:.3f} ({first - im.lobovsky_gauge(gauge)[1]:+.3f})")
        print(f"{label}: the surge first reads 0.02 H at " + ", ".join(cells) + " tau (experiment's records' mean)")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2], [tuple(a.split("=", 1)) for a in sys.argv[3:]])
