"""Impact-pressure metrics of docs/studies/impact-pressures.md, the same as tests/integration/test_validation.cpp:
records in the experiments' units (tau = t sqrt(g/H), P = p / (rho g H)), the sensor's trailing
moving average (sim/probes.hpp MovingAverage), and arrival / first peak / plateau / lowest value."""
import csv
import math
from pathlib import Path


def read_experiment(path, shift=0.0):
    """(tau, P) pairs of a shared/data/validation pressure file, sorted by time; `shift` [tau] is
    added to every time (the level clock of lobovsky_clock_offset)."""
    pts = []
    for line in open(path):
        if line.startswith("#") or line.startswith("T"):
            continue
        t, p = line.strip().split(",")
        pts.append((float(t) + shift, float(p)))
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


def read_level_gauges(path=Path(__file__).resolve().parents[2] / "tests" / "validation_data" / "lobovsky_2014_levels.csv"):
    """{gauge: (x [m], (first reading of each record [tau], ...))} from lobovsky_2014_levels.csv,
    the file tests/integration/test_validation.cpp reads too."""
    gauges = {}
    for line in open(path):
        if line.startswith("#") or line.startswith("gauge"):
            continue
        name, x, *readings = line.strip().split(",")
        gauges[name] = (float(x), tuple(float(t) for t in readings))
    return gauges


# Lobovsky et al. (2014, Fig. 16, H = 300 mm): the water-level gauges H2-H4, where they stand [m]
# and when the surge first reads 0.02 H there in each of the paper's two records [tau], and the
# end wall's position.
LOBOVSKY_GAUGES = read_level_gauges()
LOBOVSKY_WALL = 1.61


def lobovsky_gauge(name):
    """(x [m], the mean of the records' first readings [tau]) of level gauge `name`."""
    x, recorded = LOBOVSKY_GAUGES[name]
    return x, sum(recorded) / len(recorded)


def lobovsky_clock_offset(data_dir):
    """How much later [tau] the experiment's pressure records start their clock than its level
    records (docs/studies/impact-pressures.md, "The release: a lifted gate, and the experiment's two clocks"):
    the surge, continued from H4 to the end wall at the speed it had from H3 to H4, reaches the
    wall at 2.686 on the level clock; p1 rises at 2.427 on the pressure clock (the raw record's
    arrival)."""
    (x3, t3), (x4, t4) = lobovsky_gauge("h3"), lobovsky_gauge("h4")
    at_wall = t4 + (t4 - t3) * (LOBOVSKY_WALL - x4) / (x4 - x3)
    return at_wall - impact(read_experiment(Path(data_dir) / "lobovsky_2014_p1.csv"))["arrival"]


# The validation cases: sensors, their experiments, H, and the averaging window in tau (0.057 tau:
# 10 ms at H = 0.3 m, 14 ms at H = 0.6 m; docs/studies/impact-pressures.md says why). `clock: levels` compares on
# the level records' clock: the experiment's pressures moved by lobovsky_clock_offset.
LOBOVSKY_SENSORS = [("p1", "lobovsky_2014_p1.csv"), ("p3", "lobovsky_2014_p3.csv"), ("p4", "lobovsky_2014_p4.csv")]
CASES = {
    "dam_break_lobovsky": dict(H=0.3, sensors=LOBOVSKY_SENSORS),
    "dam_break_lobovsky_gate": dict(H=0.3, sensors=LOBOVSKY_SENSORS, clock="levels"),
    # The experiment's narrow tank: the same sensors at mid-width, the same clocks as the sections.
    "dam_break_lobovsky_3d": dict(H=0.3, sensors=LOBOVSKY_SENSORS),
    "dam_break_lobovsky_3d_gate": dict(H=0.3, sensors=LOBOVSKY_SENSORS, clock="levels"),
    "dam_break_buchner_2d": dict(H=0.6, sensors=[("p1", "buchner_2002_pressure.csv")]),
}


def experiment_shift(case, data_dir):
    """The time [tau] added to the case's experimental records: 0, or the Lobovsky clock offset."""
    return lobovsky_clock_offset(data_dir) if CASES[case].get("clock") == "levels" else 0.0


# The averaging window in tau: 10 ms at H = 0.3 m (the averaging the issue quotes), 14 ms at 0.6 m.
WINDOW_TAU = 0.010 * math.sqrt(9.81 / 0.3)


def compare(run, case, data_dir, window_s):
    """Per sensor: (name, experiment metrics, spate metrics) with both through the window."""
    spec = CASES[case]
    H = spec["H"]
    w = window_s * math.sqrt(9.81 / H)
    out = []
    shift = experiment_shift(case, data_dir)
    for probe, data in spec["sensors"]:
        e = impact(moving_average(read_experiment(Path(data_dir) / data, shift), w))
        m = impact(moving_average(read_sensor(run, probe, H), w))
        out.append((probe, e, m))
    return out
