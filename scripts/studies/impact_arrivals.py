#!/usr/bin/env python3
"""When the pressure builds at each height of the end wall, and what that says of the two
experiments' clocks (docs/studies/impact-pressures.md, "The release: a lifted gate, and the experiment's two
clocks"). Buchner's tank (H = 0.6 m) is Lobovsky's (H = 0.3 m) scaled by two: a column 2 H long at
the end of a tank 5.366 H long. On one clock, and in tau = t sqrt(g/H), both experiments' sensors
would cross 0.3 rho g H at the same time at the same z/H. Lobovsky has no sensor at Buchner's 0.2 H,
only p3 (0.1 H) and p4 (0.267 H): their records are joined with the shape of spate's arrival along
the wall between those heights, from the wall sensors `wZZZ` (ZZZ the height in mm) of the profile
runs of scripts/studies/impact-study.

Usage: impact_arrivals.py DATA_DIR BUCHNER_RUN LOBOVSKY_RUN=LABEL ...
Arrival as the issue defines it, through the 10 / 14 ms mean (scripts/studies/impact_metrics.py)."""
import math
import sys
from pathlib import Path

from impact_metrics import WINDOW_TAU, impact, moving_average, read_experiment, read_sensor

H_LOBOVSKY, H_BUCHNER = 0.3, 0.6
BUCHNER_Z = 0.2  # Buchner's sensor, z / H
P3_Z, P4_Z = 0.030, 0.080  # Lobovsky's p3 and p4 [m]


def arrival(record):
    return impact(moving_average(record, WINDOW_TAU))["arrival"]


def wall_arrivals(run):
    """{z [m]: arrival [tau]} over the run's wall sensors wZZZ."""
    out = {}
    for f in sorted((Path(run) / "probes").glob("w[0-9][0-9][0-9].csv")):
        out[int(f.stem[1:]) / 1000] = arrival(read_sensor(run, f.stem, H_LOBOVSKY))
    return out


def main():
    data_dir, buchner_run, runs = Path(sys.argv[1]), sys.argv[2], sys.argv[3:]
    record = {name: arrival(read_experiment(data_dir / f"lobovsky_2014_{name}.csv")) for name in ("p1", "p3", "p4")}
    buchner_record = arrival(read_experiment(data_dir / "buchner_2002_pressure.csv"))
    buchner_spate = arrival(read_sensor(buchner_run, "p1", H_BUCHNER))
    print(f"records: Lobovsky p1 (0.01 H) {record['p1']:.3f}, p3 (0.1 H) {record['p3']:.3f}, "
          f"p4 (0.267 H) {record['p4']:.3f}; Buchner (0.2 H) {buchner_record:.3f}")
    print(f"spate, Buchner's case (0.2 H): {buchner_spate:.3f}")
    for spec in runs:
        run, label = spec.split("=", 1)
        along = wall_arrivals(run)
        z_b = BUCHNER_Z * H_LOBOVSKY
        t3, t4, tb = along[P3_Z], along[P4_Z], along[round(z_b, 3)]
        share = (tb - t3) / (t4 - t3)
        lobovsky_at_b = record["p3"] + share * (record["p4"] - record["p3"])
        print(f"\n{label}: arrival along the end wall [tau] at z / H")
        print("  " + "  ".join(f"{z / H_LOBOVSKY:.3f}: {t:.3f}" for z, t in along.items() if not math.isnan(t)))
        print(f"  at 0.2 H {tb:.3f} (Buchner's case {buchner_spate:.3f}: {buchner_spate - tb:+.3f});"
              f" 0.2 H is {share:.2f} of the way from p3's arrival to p4's")
        print(f"  Lobovsky's records at 0.2 H, so joined: {lobovsky_at_b:.3f}; Buchner's record"
              f" {buchner_record - lobovsky_at_b:+.3f} tau from it"
              f" ({(buchner_record - lobovsky_at_b) / math.sqrt(9.81 / H_LOBOVSKY) * 1000:+.0f} ms at H = 0.3 m)")


if __name__ == "__main__":
    main()
