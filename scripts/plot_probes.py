#!/usr/bin/env python3
"""Plots every probe of a spate run: one PNG per probe CSV, value(s) against time with units on
both axes, ready to paste in a report. `spate plot RUN_DIR` (and `spate post --plot`) run it;
it can also be run by hand:

    plot_probes.py PROBES_DIR OUT_DIR [--title TEXT] [--describe NAME=TEXT]...

PROBES_DIR holds <name>.csv files in spate's probe format (docs/cases.md, "Probe CSV files"): a
header `time[s],step,<column>[<unit>],...` and one row per sample. Writes OUT_DIR/<name>.png.
Exit 2 when there is nothing to plot or a file is not a probe file (the message says which).
"""
import argparse
import csv
import math
import os
import re
import sys
import textwrap

try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:
    print("spate plot needs matplotlib (Debian: apt-get install python3-matplotlib)", file=sys.stderr)
    sys.exit(2)

COLUMN = re.compile(r"^([^\[\]]+?)(?:\[([^\[\]]*)\])?$")
# What a probe measures, from the name of its first value column (probe_columns in solver/sim/probes.cpp).
QUANTITY = [
    (re.compile(r"^(p|pressure)"), "pressure"),
    (re.compile(r"^v[xyz]$"), "velocity"),
    (re.compile(r"^f[xyz]$"), "force"),
    (re.compile(r"^height"), "water height"),
    (re.compile(r"^front"), "front position"),
]


def parse_column(text):
    m = COLUMN.match(text.strip())
    return (m.group(1).strip(), m.group(2) or "") if m else (text.strip(), "")


def read_probe(path):
    """(columns [(name, unit)], time [s], {column: values}) of a probe CSV."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    if not rows or len(rows[0]) < 3:
        raise ValueError("not a probe file: expected a header 'time[s],step,<column>[<unit>],...'")
    columns = [parse_column(c) for c in rows[0]]
    if columns[0][0] != "time" or columns[1][0] != "step":
        raise ValueError(f"not a probe file: the header starts '{rows[0][0]},{rows[0][1]}', expected 'time[s],step'")
    time, values = [], {c: [] for c in columns[2:]}
    for line, row in enumerate(rows[1:], start=2):
        if len(row) != len(columns):
            raise ValueError(f"line {line}: {len(row)} values, the header has {len(columns)} columns")
        time.append(float(row[0]))
        for c, v in zip(columns[2:], row[2:]):
            values[c].append(float(v))
    return columns[2:], time, values


def quantity(columns):
    name = columns[0][0]
    for pattern, label in QUANTITY:
        if pattern.match(name):
            return label
    return name


def plot(path, out_dir, title, description=""):
    name = os.path.splitext(os.path.basename(path))[0]
    columns, time, values = read_probe(path)
    # One panel per unit, in the order the units first appear (a body probe: position, angle,
    # velocities, force, torque), so that no quantity is flattened by another's scale.
    groups = []
    for c in columns:
        for g in groups:
            if g[0][1] == c[1]:
                g.append(c)
                break
        else:
            groups.append([c])
    fig, axes = plt.subplots(len(groups), 1, figsize=(8, 2.2 + 2.3 * len(groups)), dpi=150, sharex=True, squeeze=False)
    for ax, group in zip(axes[:, 0], groups):
        for c in group:
            ys = values[c]
            # A front with no water deep enough reads -inf: leave those samples out.
            ax.plot(time, [y if math.isfinite(y) else math.nan for y in ys], lw=1.2, label=c[0])
        label = quantity(group)
        unit = group[0][1]
        ax.set_ylabel(f"{label} [{unit}]" if unit else label)
        ax.grid(True, color="0.85", lw=0.6)
        ax.set_xlim(left=min(time) if time else 0)
        if len(group) > 1 or len(groups) > 1:
            ax.legend(frameon=False)
    axes[-1, 0].set_xlabel("time [s]")
    heading = f"{name}, {description}" if description else name
    axes[0, 0].set_title("\n".join(textwrap.wrap(f"{title}: {heading}" if title else heading, 80)), fontsize=11)
    fig.tight_layout()
    out = os.path.join(out_dir, name + ".png")
    fig.savefig(out)
    plt.close(fig)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("probes_dir")
    ap.add_argument("out_dir")
    ap.add_argument("--title", default="", help="the case's name")
    ap.add_argument("--describe", action="append", default=[], metavar="NAME=TEXT", help="what probe NAME measures, where")
    args = ap.parse_args()
    descriptions = dict(d.split("=", 1) for d in args.describe if "=" in d)
    files = sorted(f for f in os.listdir(args.probes_dir) if f.endswith(".csv")) if os.path.isdir(args.probes_dir) else []
    if not files:
        print(f"{args.probes_dir}: no probe files (<name>.csv) to plot", file=sys.stderr)
        return 2
    os.makedirs(args.out_dir, exist_ok=True)
    for f in files:
        path = os.path.join(args.probes_dir, f)
        try:
            plot(path, args.out_dir, args.title, descriptions.get(f[:-4], ""))
        except (ValueError, OSError) as e:
            print(f"{path}: {e}", file=sys.stderr)
            return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
