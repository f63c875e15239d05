"""Impact-pressure metrics of docs/validation.md, the same as tests/integration/test_validation.cpp:
records in the experiments' units (tau = t sqrt(g/H), P = p / (rho g H)), the sensor's trailing
moving average (sim/probes.hpp MovingAverage), and arrival / first peak / plateau / lowest value."""
import csv
import math
from pathlib import Path


def read_experiment(path):
    """(tau, P) pairs of a shared/data/validation pressure file, sorted by time."""
    pts = []
    for line in open(path):
        if line.startswith("#") or line.startswith("T"):
            continue
        t, p = line.strip().split(",")
        pts.append((float(t), float(p)))
    return sorted(pts, key=lambda x: x[0])


def read_sensor(run, probe, H, g=9.81, rho=1000.0):
    """A spate sensor CSV as (tau, P), unaveraged: the first column is the time in seconds; the
    reading is the column `pressure_instant...` when the sensor has a window, else the first column
    named p or starting with 'pressure'."""
    with open(Path(run) / "probes" / f"{probe}.csv") as f:
        rows = list(csv.reader(f))
    head = rows[0]
    instant = [k for k, name in enumerate(head) if name.startswith("pressure_instant")]
    col = instant[0] if instant else next(k for k, name in enumerate(head) if name == "p" or name.startswith("p[") or name.startswith("pressure"))
    scale = math.sqrt(g / H)
    return [(float(r[0]) * scale, float(r[col]) / (rho * g * H)) for r in rows[1:]]


def moving_average(record, window):
    """The mean of the piecewise-linear record over the trailing window (all of it so far while
    shorter), at every sample."""
    out = []
    for k, (t, v) in enumerate(record):
        start = max(t - window, record[0][0])
        if window <= 0 or t <= start:
            out.append((t, v))
            continue
        integral = 0.0
        j = k
        while j > 0 and record[j][0] > start:
            t0, v0 = record[j - 1]
            t1, v1 = record[j]
            a = max(t0, start)
            va = v0 + (v1 - v0) * (a - t0) / (t1 - t0) if t1 > t0 else v1
            integral += 0.5 * (va + v1) * (t1 - a)
            j -= 1
        out.append((t, integral / (t - start)))
    return out


def impact(record):
    """arrival: first of three consecutive samples above 0.3; peak: largest within one tau after
    it; plateau: mean over 1 <= tau - arrival <= 2; lowest: smallest after the arrival."""
    arrival = next((record[k][0] for k in range(len(record) - 2) if all(record[k + i][1] > 0.3 for i in range(3))), math.nan)
    if math.isnan(arrival):
        return dict(arrival=math.nan, peak=math.nan, plateau=math.nan, lowest=math.nan)
    peak = max(v for t, v in record if arrival <= t <= arrival + 1)
    lowest = min(v for t, v in record if t >= arrival)
    lo, hi = arrival + 1, arrival + 2
    integral = 0.0
    for (t0, v0), (t1, v1) in zip(record, record[1:]):
        a, b = max(t0, lo), min(t1, hi)
        if b <= a or t1 <= t0:
            continue
        at = lambda t: v0 + (v1 - v0) * (t - t0) / (t1 - t0)  # noqa: E731
        integral += 0.5 * (at(a) + at(b)) * (b - a)
    plateau = integral / (hi - lo) if record[-1][0] >= hi else math.nan
    return dict(arrival=arrival, peak=peak, plateau=plateau, lowest=lowest)


# The validation cases: sensors, their experiments, H, and the averaging window in tau (0.057 tau:
# 10 ms at H = 0.3 m, 14 ms at H = 0.6 m; docs/validation.md says why).
CASES = {
    "dam_break_lobovsky": dict(H=0.3, sensors=[("p1", "lobovsky_2014_p1.csv"), ("p3", "lobovsky_2014_p3.csv"),
                                                ("p4", "lobovsky_2014_p4.csv")]),
    "dam_break_buchner_2d": dict(H=0.6, sensors=[("p1", "buchner_2002_pressure.csv")]),
}


# The averaging window in tau: 10 ms at H = 0.3 m (the averaging the issue quotes), 14 ms at 0.6 m.
WINDOW_TAU = 0.010 * math.sqrt(9.81 / 0.3)


def compare(run, case, data_dir, window_s):
    """Per sensor: (name, experiment metrics, spate metrics) with both through the window."""
    spec = CASES[case]
    H = spec["H"]
    w = window_s * math.sqrt(9.81 / H)
    out = []
    for probe, data in spec["sensors"]:
        e = impact(moving_average(read_experiment(Path(data_dir) / data), w))
        m = impact(moving_average(read_sensor(run, probe, H), w))
        out.append((probe, e, m))
    return out
