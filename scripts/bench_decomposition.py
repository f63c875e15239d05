#!/usr/bin/env python3
"""Multi-device and MPI measurements for docs/performance.md, printed as Markdown.

  scripts/bench_decomposition.py [--spate build/bin/spate] [--steps 20] [--until 1.0] [--mpiexec mpiexec]

1. devices: `spate bench` on the column case (193,020 particles at its default dp = 0.01) with
   D = 1 and D = 2 on the same threads, and with one thread per device.
2. ranks: the same with 2 MPI ranks (one thread each) against 1 rank.
3. cpu: CPU seconds per step of each split (robust on a shared machine).
4. ghosts: ghost particles as a fraction of owned for D = 2, 3, 4 (from the bench runs).
5. balance: the 2D dam break over its first `--until` seconds on 4 devices with balancing every
   100 steps and without; the imbalance (max/mean owned particles) at every snapshot, counted from
   the slab pieces.
"""
import argparse
import json
import os
import re
import resource
import subprocess
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def env():
    e = dict(os.environ)
    e.setdefault("OMPI_ALLOW_RUN_AS_ROOT", "1")
    e.setdefault("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
    e.setdefault("OMPI_MCA_rmaps_base_oversubscribe", "1")
    e.setdefault("OMP_WAIT_POLICY", "passive")
    return e


def bench(args, devices, threads, ranks=1):
    cmd = [args.spate, "bench", str(ROOT / "cases/dam_break_column_3d.yaml"), "--steps", str(args.steps), "--devices",
           str(devices), "--threads", str(threads), "--json"]
    if ranks > 1:
        cmd = [args.mpiexec, "-n", str(ranks), *cmd]
    out = subprocess.run(cmd, capture_output=True, text=True, check=True, env=env()).stdout
    j = json.loads(out[out.index("{"):])
    j["command"] = ("mpirun -np 2 " if ranks > 1 else "") + " ".join(["spate"] + cmd[cmd.index("bench"):])
    return j


def cpu_seconds_per_step(args, devices, threads, ranks=1, short=2, long=12):
    """CPU time (user + sys, all threads and ranks) per step: the difference of two runs that differ
    only in their step count, so set-up and the final checkpoint cancel. Unlike wall time it
    measures the work of a split even on a machine shared with other jobs."""
    used = []
    for steps in (short, long):
        with tempfile.TemporaryDirectory() as tmp:
            cmd = [args.spate, "run", str(ROOT / "cases/dam_break_column_3d.yaml"), "--steps", str(steps), "--devices", str(devices),
                   "--threads", str(threads), "--quiet", "--out", tmp, "--set", "output.interval=0", "--set", "probes=[]"]
            if ranks > 1:
                cmd = [args.mpiexec, "-n", str(ranks), *cmd]
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            subprocess.run(cmd, check=True, env=env(), capture_output=True)
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            used.append(after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime)
    return (used[1] - used[0]) / (long - short)


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
    cmd = [args.spate, "run", str(ROOT / "cases/dam_break_2d.yaml"), "--until", str(args.until), "--devices", "4",
           "--threads", "1", "--quiet", "--out", str(out), "--set", f"decomposition.balance_every={balance_every}"]
    subprocess.run(cmd, check=True, env=env())
    with open(out / "summary.json") as f:
        s = json.load(f)
    return s, imbalance_series(out), "spate " + " ".join(cmd[1:-2]).replace(str(ROOT) + "/", "").replace(str(work), "OUT")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--spate", default=str(ROOT / "build/bin/spate"))
    ap.add_argument("--steps", type=int, default=20)
    ap.add_argument("--until", type=float, default=1.0)
    ap.add_argument("--mpiexec", default="mpiexec")
    ap.add_argument("--skip", default="", help="comma list of parts to skip: devices,ranks,cpu,ghosts,balance")
    args = ap.parse_args()
    skip = set(args.skip.split(","))
    cores = os.cpu_count()
    print(f"Machine: {cores} cores, load average {os.getloadavg()[0]:.1f} at the start.\n")

    rows = []
    if "devices" not in skip:
        rows += [("1 rank, D = 1, 2 threads", bench(args, 1, 2)), ("1 rank, D = 2, 2 threads (1 per device)", bench(args, 2, 2)),
                 ("1 rank, D = 1, 1 thread", bench(args, 1, 1))]
    if "ranks" not in skip:
        rows += [("2 ranks x D = 1, 1 thread each", bench(args, 1, 1, ranks=2))]
    if rows:
        base = rows[0][1]["seconds_per_step"]
        print("| run | s/step | particle-steps/s | speed-up vs first row | ghosts | command |")
        print("|---|---|---|---|---|---|")
        for name, j in rows:
            print(f"| {name} | {j['seconds_per_step']:.3f} | {j['particle_steps_per_second']:.3g} | "
                  f"{base / j['seconds_per_step']:.2f} | {j['ghost_particles']} | `{j['command']}` |")
        print()

    if "cpu" not in skip:
        print("| run | CPU s/step (all threads, all ranks) | ratio to D = 1, 1 thread |")
        print("|---|---|---|")
        base = None
        for name, d, th, r in (("1 rank, D = 1, 1 thread", 1, 1, 1), ("1 rank, D = 1, 2 threads", 1, 2, 1),
                               ("1 rank, D = 2, 1 thread each", 2, 2, 1), ("2 ranks x D = 1, 1 thread each", 1, 1, 2)):
            c = cpu_seconds_per_step(args, d, th, r)
            base = base or c
            print(f"| {name} | {c:.3f} | {c / base:.2f} |")
        print()

    if "ghosts" not in skip:
        print("| slabs | ghost particles | ghosts / owned |")
        print("|---|---|---|")
        for d in (2, 3, 4):
            j = bench(args, d, 1) if d != 2 or not rows else rows[1][1]
            print(f"| {d} | {j['ghost_particles']} | {j['ghost_particles'] / j['particles']['total']:.3f} |")
        print()

    if "balance" not in skip:
        with tempfile.TemporaryDirectory() as tmp:
            work = Path(tmp)
            results = {k: dam_break(args, k, work) for k in (100, 0)}
        print("| t [s] | imbalance, balance_every = 100 | imbalance, no balancing |")
        print("|---|---|---|")
        a, b = results[100][1], results[0][1]
        for (time_a, ia, _), (_, ib, _) in zip(a, b):
            print(f"| {time_a:.2f} | {ia:.3f} | {ib:.3f} |")
        for k in (100, 0):
            s, series, cmd = results[k]
            values = [v for _, v, _ in series]
            print(f"\nbalance_every = {k}: {s['final_step']} steps, wall {s['wall_seconds']:.1f} s, imbalance mean "
                  f"{sum(values) / len(values):.3f}, max {max(values):.3f}, final device_particles {s['device_particles']}, "
                  f"face moves {s.get('face_moves')}, ghosts {s['ghost_particles']}; `{cmd}`")


if __name__ == "__main__":
    main()
