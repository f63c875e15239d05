#!/usr/bin/env python3
"""Multi-device and MPI measurements for docs/performance.md, printed as Markdown.

  flock /work/wt/machine.lock scripts/bench_decomposition.py [--rounds 5] [--steps 10] [--skip balance]

The machine this runs on (a 2-core VM) changes speed by +-30 % from one run to the next, so a
single run per configuration proves nothing. This script therefore

1. scaling: runs `spate bench` on the ~200k-particle column case
   (`cases/dam_break_column_3d.yaml --set dp=0.0098 --set time.dt=auto`, 203,108 particles) in
   several rounds; each round runs every configuration once, in a rotated order:
   1 rank D = 1 on 1 thread (the baseline), D = 1 on 2 threads, D = 2, 3, 4 (one thread per
   device, sharing the 2 cores), `mpirun -np 2` with D = 1 and with D = 2. It reports the median
   seconds per step of each configuration and the median over rounds of the per-round speed-up
   against the baseline of the same round (robust to slow drifts of the machine's speed).
2. ceiling: in each round also two independent 1-thread D = 1 runs at the same time. Twice the
   baseline's time over their mean time is the throughput two perfectly independent jobs get on
   this VM: no decomposition can beat it.
3. ghosts: ghost particles as a fraction of owned, from the scaling runs (at their end, after the
   balancer's passes).
4. balance: the 2D dam break over its first `--until` seconds on 4 devices with balancing every
   100 steps and without; the imbalance (max/mean owned particles) at every snapshot, counted from
   the slab pieces.

Run it under the machine lock on an otherwise idle machine. `--raw FILE` keeps every JSON answer.
"""
import argparse
import json
import os
import re
import statistics
import subprocess
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
COLUMN = ["cases/dam_break_column_3d.yaml", "--set", "dp=0.0098", "--set", "time.dt=auto"]

# (label, ranks, devices, threads per process)
CONFIGS = [
    ("1 rank, D = 1, 1 thread", 1, 1, 1),
    ("1 rank, D = 1, 2 threads", 1, 1, 2),
    ("1 rank, D = 2 (1 thread per device)", 1, 2, 2),
    ("1 rank, D = 3 (3 workers on 2 cores)", 1, 3, 2),
    ("1 rank, D = 4 (4 workers on 2 cores)", 1, 4, 2),
    ("2 ranks, D = 1, 1 thread each", 2, 1, 1),
    ("2 ranks, D = 2 each (4 workers on 2 cores)", 2, 2, 2),
]
BASE = CONFIGS[0][0]


def env():
    e = dict(os.environ)
    e.setdefault("OMPI_ALLOW_RUN_AS_ROOT", "1")
    e.setdefault("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
    e.setdefault("OMPI_MCA_rmaps_base_oversubscribe", "1")
    # Ranks that wait for a neighbour yield their core instead of spinning (matters only when there
    # are more workers than cores).
    e.setdefault("OMPI_MCA_mpi_yield_when_idle", "1")
    return e


def bench_command(args, ranks, devices, threads):
    cmd = [args.spate, "bench", *COLUMN, "--steps", str(args.steps), "--devices", str(devices), "--threads", str(threads), "--json"]
    if ranks > 1:
        cmd = [args.mpirun, "--allow-run-as-root", "--oversubscribe", "-np", str(ranks), *cmd]
    return cmd


def parse(out):
    return json.loads(out[out.index("{"):])


def printable(cmd, args):
    return " ".join(cmd).replace(args.spate, "build/bin/spate").replace(args.mpirun, "mpirun")


def bench(args, ranks, devices, threads):
    cmd = bench_command(args, ranks, devices, threads)
    p = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT, env=env())
    if p.returncode != 0:
        raise SystemExit(f"failed ({p.returncode}): {' '.join(cmd)}\n{p.stdout}\n{p.stderr}")
    return parse(p.stdout)


def concurrent_pair(args):
    """Two independent 1-thread runs started together; their seconds per step."""
    cmd = bench_command(args, 1, 1, 1)
    procs = [subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=ROOT, env=env()) for _ in range(2)]
    outs = [p.communicate() for p in procs]
    for p, (out, err) in zip(procs, outs):
        if p.returncode != 0:
            raise SystemExit(f"failed ({p.returncode}): {' '.join(cmd)}\n{out}\n{err}")
    return [parse(out) for out, _ in outs]


def scaling(args, raw):
    times = {label: [] for label, *_ in CONFIGS}
    ratios = {label: [] for label, *_ in CONFIGS}
    ratios_t2 = {label: [] for label, *_ in CONFIGS}
    shares = {label: [] for label, *_ in CONFIGS}
    ceiling, last = [], {}
    for r in range(args.rounds):
        # Rotate the order so that no configuration always runs first (or right after the pair).
        order = CONFIGS[r % len(CONFIGS):] + CONFIGS[:r % len(CONFIGS)]
        this_round = {}
        for label, ranks, devices, threads in order:
            j = bench(args, ranks, devices, threads)
            this_round[label] = j["seconds_per_step"]
            shares[label].append(busy_share(j))
            last[label] = j
            raw.append({"round": r, "config": label, **j})
        pair = concurrent_pair(args)
        raw.append({"round": r, "config": "concurrent pair", "runs": pair})
        pair_mean = statistics.mean(p["seconds_per_step"] for p in pair)
        ceiling.append(2 * this_round[BASE] / pair_mean)
        for label in times:
            times[label].append(this_round[label])
            ratios[label].append(this_round[BASE] / this_round[label])
            ratios_t2[label].append(this_round["1 rank, D = 1, 2 threads"] / this_round[label])
        print(f"round {r + 1}/{args.rounds} (s/step in table order): " + ", ".join(f"{this_round[label]:.3f}" for label, *_ in CONFIGS) +
              f"; pair {pair_mean:.3f} (ceiling {ceiling[-1]:.2f})", flush=True)
    print()
    print(f"Medians over {args.rounds} rounds, {args.steps} timed steps per run (s/step includes the final checkpoint):\n")
    print("| configuration | median s/step | min-max s/step | median speed-up vs 1 rank, D = 1, 1 thread | "
          "median speed-up vs D = 1, 2 threads | median busy share | face moves | command |")
    print("|---|---|---|---|---|---|---|---|")
    for label, ranks, devices, threads in CONFIGS:
        t = times[label]
        cmd = printable(bench_command(args, ranks, devices, threads), args)
        print(f"| {label} | {statistics.median(t):.3f} | {min(t):.3f}-{max(t):.3f} | {statistics.median(ratios[label]):.2f} | "
              f"{statistics.median(ratios_t2[label]):.2f} | {statistics.median(shares[label]):.2f} | {last[label].get('face_moves')} | `{cmd}` |")
    print("\nBusy share: the slabs' seconds in their own neighbour loops and sort over slabs x stepping "
          "seconds, within one run (so independent of the machine's speed that day); the rest is waiting "
          "for other slabs and the per-particle updates outside the loops.")
    print(f"\nMachine ceiling (two 1-thread runs at once vs one alone, 2 = perfect): median "
          f"{statistics.median(ceiling):.2f}, rounds {', '.join(f'{c:.2f}' for c in ceiling)}.\n")
    print("Per-round speed-ups vs the baseline:\n")
    for label in times:
        print(f"- {label}: " + ", ".join(f"{v:.2f}" for v in ratios[label]))
    print()
    return last


def busy_share(j):
    """Fraction of the slabs' time spent in their own loops and sort (device_busy_seconds) rather than
    waiting or in the per-particle updates, within one run."""
    busy = j.get("device_busy_seconds") or []
    stepping = j.get("stepping_seconds") or 0
    return sum(busy) / (len(busy) * stepping) if busy and stepping else float("nan")


def ghosts(last):
    print("| run | ghost particles | ghosts / owned | device_particles | device_busy_seconds |")
    print("|---|---|---|---|---|")
    for label, j in last.items():
        if j["ghost_particles"] == 0:
            continue
        busy = ", ".join(f"{b:.2f}" for b in j.get("device_busy_seconds", []))
        print(f"| {label} | {j['ghost_particles']:,} | {j['ghost_particles'] / j['particles']['total']:.3f} | "
              f"{', '.join(f'{n:,}' for n in j.get('device_particles', []))} | {busy} |")
    print()


def imbalance_series(out_dir):
    """(time, max/mean, counts) for every indexed snapshot, from the point counts of its pieces."""
    series = []
    snapshots = out_dir / "snapshots"
    pvd = (out_dir / "particles.pvd").read_text()
    for time, file in re.findall(r'timestep="([^"]+)"[^>]*file="([^"]+)"', pvd):
        vtm = out_dir / file
        counts = []
        for piece in sorted((snapshots / vtm.stem).glob("slab_*.vtp")):
            with open(piece, "rb") as f:
                head = f.read(400).decode("latin-1")
            counts.append(int(re.search(r'NumberOfPoints="(\d+)"', head).group(1)))
        mean = sum(counts) / len(counts)
        series.append((float(time), max(counts) / mean, counts))
    return series


def dam_break(args, balance_every, work):
    out = work / f"balance_{balance_every}"
    cmd = [args.spate, "run", "cases/dam_break_2d.yaml", "--until", str(args.until), "--devices", "4",
           "--threads", "1", "--quiet", "--out", str(out), "--set", f"decomposition.balance_every={balance_every}"]
    subprocess.run(cmd, check=True, env=env(), cwd=ROOT)
    with open(out / "summary.json") as f:
        s = json.load(f)
    return s, imbalance_series(out), printable(cmd[:-4] + cmd[-2:], args)


def balance(args):
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        results = {k: dam_break(args, k, work) for k in (100, 0)}
    print("| t [s] | imbalance, balance_every = 100 | imbalance, no balancing |")
    print("|---|---|---|")
    a, b = results[100][1], results[0][1]
    for k, ((time_a, ia, _), (_, ib, _)) in enumerate(zip(a, b)):
        if k % 2 == 0:
            print(f"| {time_a:.2f} | {ia:.3f} | {ib:.3f} |")
    for k in (100, 0):
        s, series, cmd = results[k]
        values = [v for t, v, _ in series]
        after0 = [(v, t) for t, v, _ in series if t > 0]
        worst = max(after0) if after0 else (float("nan"), 0)
        print(f"\nbalance_every = {k}: {s['final_step']} steps, wall {s['wall_seconds']:.1f} s, imbalance mean "
              f"{sum(values) / len(values):.3f}, largest after t = 0 {worst[0]:.3f} (t = {worst[1]:.2f} s), final device_particles "
              f"{s['device_particles']}, face moves {s.get('face_moves')}, ghosts {s['ghost_particles']}; `{cmd}`")
        history = s.get("imbalance_history") or []
        if history:
            print(f"  measured phase imbalance before each of its {len(history)} passes: mean {statistics.mean(history):.3f}, "
                  f"median {statistics.median(history):.3f}, max {max(history):.3f} (first {history[0]:.3f})")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--spate", default=str(ROOT / "build/bin/spate"))
    ap.add_argument("--mpirun", default="mpirun")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--steps", type=int, default=10)
    ap.add_argument("--until", type=float, default=1.0)
    ap.add_argument("--raw", help="write every JSON answer of the scaling runs to this file")
    ap.add_argument("--skip", default="", help="comma list of parts to skip: scaling,ghosts,balance")
    args = ap.parse_args()
    skip = set(args.skip.split(","))
    print(f"Machine: {os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f} at the start.\n")
    raw = []
    last = {}
    if "scaling" not in skip:
        last = scaling(args, raw)
    if "ghosts" not in skip and last:
        ghosts(last)
    if args.raw:
        Path(args.raw).write_text(json.dumps(raw, indent=1))
    if "balance" not in skip:
        balance(args)


if __name__ == "__main__":
    main()
