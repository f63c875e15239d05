#!/usr/bin/env python3
"""Drives build/bin/spate through its command line to check the decomposition: results must be
bit-identical whatever the split into R ranks x D devices (spate compare --tolerance 0), a
restart may change the split, the balancer moves faces while fluid crosses them, and bad splits
are refused with exit code 2. Each run writes <work>/<name>/summary.json and its checkpoints.

Splits are written RxD (ranks x devices); R > 1 runs under mpiexec.
"""
import argparse
import itertools
import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

RUN_TIMEOUT = 600  # seconds; a hang fails the test instead of blocking the suite


def fail(message):
    print(f"FAIL: {message}", flush=True)
    sys.exit(1)


def parse_split(text):
    try:
        r, d = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text}: expected RxD, e.g. 2x1")
    return r, d


class Spate:
    def __init__(self, args):
        self.exe = args.spate
        self.case = args.case
        self.sets = [item for s in args.set for item in ("--set", s)]
        self.mpiexec = args.mpiexec
        self.mpiexec_args = args.mpiexec_args.split() if args.mpiexec_args else []
        self.work = Path(args.work)
        self.work.mkdir(parents=True, exist_ok=True)

    def command(self, split, extra):
        ranks, devices = split
        cmd = [self.exe, "run", self.case, *self.sets, "--threads", "1", "--devices", str(devices), "--quiet", *extra]
        if ranks > 1:
            if not self.mpiexec:
                fail(f"split {ranks}x{devices} needs mpiexec (pass --mpiexec)")
            cmd = [self.mpiexec, "-n", str(ranks), *self.mpiexec_args, *cmd]
        return cmd

    def run(self, name, split, extra=(), expect=0):
        out = self.work / name
        shutil.rmtree(out, ignore_errors=True)
        cmd = self.command(split, ["--out", str(out), *extra])
        print("$ " + " ".join(cmd), flush=True)
        begin = time.monotonic()
        try:
            p = subprocess.run(cmd, capture_output=True, text=True, timeout=RUN_TIMEOUT, env=mpi_env())
        except subprocess.TimeoutExpired:
            fail(f"{name}: no answer after {RUN_TIMEOUT} s (hang?)")
        print(f"  exit {p.returncode} in {time.monotonic() - begin:.1f} s", flush=True)
        if p.returncode != expect:
            print(p.stdout)
            print(p.stderr)
            fail(f"{name}: exit code {p.returncode}, expected {expect}")
        return out, p

    def compare(self, a, b):
        p = subprocess.run([self.exe, "compare", str(a), str(b), "--tolerance", "0"], capture_output=True, text=True)
        if p.returncode != 0:
            print(p.stdout, p.stderr)
            fail(f"{a} and {b} differ (spate compare --tolerance 0 exit {p.returncode})")
        print(f"  MATCH {a.parent.parent.name} {b.parent.parent.name}", flush=True)


def mpi_env():
    env = dict(os.environ)
    # OpenMPI refuses root and more ranks than cores unless told; CI containers run as root on
    # small machines. Yielding when idle keeps polling ranks from starving each other there.
    env.setdefault("OMPI_ALLOW_RUN_AS_ROOT", "1")
    env.setdefault("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
    env.setdefault("OMPI_MCA_rmaps_base_oversubscribe", "1")
    env.setdefault("OMPI_MCA_mpi_yield_when_idle", "1")
    env.setdefault("OMP_WAIT_POLICY", "passive")
    return env


def summary(out):
    with open(out / "summary.json") as f:
        return json.load(f)


def final_checkpoint(out):
    s = summary(out)
    path = Path(s["last_checkpoint"])
    if not path.is_absolute() and not path.exists():
        path = out / "checkpoints" / path.name
    if not path.exists():
        fail(f"{out}: last_checkpoint {path} missing")
    return path


def split_name(split):
    return f"r{split[0]}d{split[1]}"


def check_summary(out, split, steps):
    s = summary(out)
    ranks, devices = split
    if s["steps"] != steps:
        fail(f"{out}: {s['steps']} steps, expected {steps}")
    if s["ranks"] != ranks or s["devices"] != devices:
        fail(f"{out}: summary says {s['ranks']} ranks x {s['devices']} devices, expected {ranks}x{devices}")
    counts = s["device_particles"]
    if len(counts) != ranks * devices:
        fail(f"{out}: {len(counts)} device_particles entries for {ranks * devices} slabs")
    remaining = s["particles"]["total"] - s.get("removed_particles", 0)
    if sum(counts) != remaining:
        fail(f"{out}: device_particles add up to {sum(counts)}, not {remaining}")
    if ranks * devices > 1 and s["ghost_particles"] <= 0:
        fail(f"{out}: no ghost particles with {ranks * devices} slabs")
    snapshots = out / "snapshots"
    if snapshots.exists():
        for vtm in snapshots.glob("*.vtm"):
            pieces = sorted((snapshots / vtm.stem).glob("slab_*.vtp"))
            if len(pieces) != ranks * devices:
                fail(f"{vtm}: {len(pieces)} slab pieces for {ranks * devices} slabs")
    return s


PARAVIEW_CHECK = """
import sys
from paraview.simple import PVDReader, MergeBlocks
reader = PVDReader(FileName=sys.argv[1])
t = reader.TimestepValues[-1] if reader.TimestepValues else 0.0
merged = MergeBlocks(Input=reader)
merged.UpdatePipeline(t)
print("POINTS", merged.GetDataInformation().GetNumberOfPoints(), "BLOCKS", reader.GetDataInformation().GetNumberOfDataSets())
"""


def check_paraview(pvbatch, out, total, slabs):
    """ParaView opens the last snapshot of the run as one dataset holding every particle."""
    script = out / "check_snapshot.py"
    script.write_text(PARAVIEW_CHECK)
    p = subprocess.run([pvbatch, str(script), str(out / "particles.pvd")], capture_output=True, text=True, timeout=300)
    line = next((l for l in p.stdout.splitlines() if l.startswith("POINTS")), None)
    if p.returncode != 0 or line is None:
        print(p.stdout, p.stderr)
        fail(f"pvbatch could not read {out / 'particles.pvd'}")
    points, blocks = int(line.split()[1]), int(line.split()[3])
    if points != total or blocks != slabs:
        fail(f"ParaView reads {points} points in {blocks} partitions from {out.name}, expected {total} in {slabs}")
    print(f"  ParaView opens {out.name}/particles.pvd as one dataset: {points} points in {blocks} partitions")


def check_removed(args, out):
    """--expect-removed: fluid was removed through open sides (and as many in every run)."""
    removed = summary(out).get("removed_particles", 0)
    if args.expect_removed and removed <= 0:
        fail(f"{out}: no fluid removed through open sides")
    return removed


def cmd_splits(args):
    """Runs every split and compares every pair of final checkpoints, including runs already in
    <work> from another test (the MPI splits compare with the in-process ones)."""
    if args.fresh:
        # Runs left by an older build must not take part in the comparison.
        shutil.rmtree(args.work, ignore_errors=True)
    spate = Spate(args)
    for split in args.splits:
        out, _ = spate.run(split_name(split), split, ["--steps", str(args.steps)])
        s = check_summary(out, split, args.steps)
        check_removed(args, out)
        print(f"  {split_name(split)}: device_particles {s['device_particles']}, imbalance {s['imbalance']:.3f}, "
              f"ghosts {s['ghost_particles']}, migrated {s.get('migrated_particles')}, face moves {s.get('face_moves')}, "
              f"removed {s.get('removed_particles', 0)}")
        if args.expect_migration and split[0] * split[1] > 1 and s["migrated_particles"] <= 0:
            fail(f"{split_name(split)}: no particle crossed a face (--expect-migration)")
    if args.pvbatch:
        last = args.splits[-1]
        out = spate.work / split_name(last)
        check_paraview(args.pvbatch, out, summary(out)["particles"]["total"], last[0] * last[1])
    runs = sorted(p for p in spate.work.glob("r*d*") if (p / "summary.json").exists() and summary(p)["steps"] == args.steps)
    names = {p.name for p in runs}
    for split in args.splits:
        if split_name(split) not in names:
            fail(f"{split_name(split)} did not leave a summary")
    if len(runs) < 2:
        fail("fewer than two runs to compare")
    removed = {check_removed(args, p) for p in runs}
    if len(removed) != 1:
        fail(f"the splits removed different numbers of particles: {sorted(removed)}")
    for a, b in itertools.combinations(runs, 2):
        spate.compare(final_checkpoint(a), final_checkpoint(b))
    print(f"PASS: {len(runs)} splits ({', '.join(p.name for p in runs)}) bit-identical after {args.steps} steps")


def cmd_restart(args):
    """A run with the first split writes a checkpoint half way; continuing it with each other split
    must end bit-identical to the uninterrupted run."""
    spate = Spate(args)
    half = args.steps // 2
    first = args.splits[0]
    out, _ = spate.run("restart_from_" + split_name(first), first,
                       ["--steps", str(args.steps), "--checkpoint-every", str(half)])
    middle = out / "checkpoints" / f"checkpoint_step_{half:08d}.h5"
    if not middle.exists():
        fail(f"{middle} missing")
    reference = final_checkpoint(out)
    if args.expect_removed:
        with open(out / "summary.json") as f:
            total = json.load(f)["removed_particles"]
        # The checkpoint half way must already count some: the restart has to carry them on.
        import h5py
        with h5py.File(middle, "r") as f:
            if int(f.attrs["removed_particles"]) <= 0:
                fail(f"{middle}: no removed particles recorded yet (choose more --steps)")
    for split in args.splits[1:]:
        cont, _ = spate.run(f"restart_{split_name(first)}_as_{split_name(split)}", split,
                            ["--steps", str(args.steps - half), "--restart", str(middle)])
        s = summary(cont)
        if s["final_step"] != args.steps:
            fail(f"{cont}: ended at step {s['final_step']}, expected {args.steps}")
        if args.expect_removed and s["removed_particles"] != total:
            fail(f"{cont}: {s['removed_particles']} removed in all, the uninterrupted run {total}")
        spate.compare(reference, final_checkpoint(cont))
    print(f"PASS: restarting a {first[0]}x{first[1]} checkpoint at step {half} as "
          f"{', '.join(f'{r}x{d}' for r, d in args.splits[1:])} continues bit-identically")


def cmd_balance(args):
    """With frequent balancing the faces must move, fluid must cross faces, the imbalance must drop,
    and the answer must still equal the single-slab run."""
    spate = Spate(args)
    split = args.splits[0]
    start, _ = spate.run("balance_start", split, ["--steps", "0"])
    out, _ = spate.run("balance", split, ["--steps", str(args.steps)])
    single, _ = spate.run("balance_single", (1, 1), ["--steps", str(args.steps)])
    s0, s = summary(start), check_summary(out, split, args.steps)
    history = s["imbalance_history"]
    print(f"  initial device_particles {s0['device_particles']} (imbalance {s0['imbalance']:.3f})")
    print(f"  final   device_particles {s['device_particles']} (imbalance {s['imbalance']:.3f})")
    print(f"  imbalance history {[round(v, 3) for v in history]}")
    print(f"  face moves {s['face_moves']}, migrated {s['migrated_particles']}, handed over {s['handed_over_particles']}")
    if not history:
        fail("imbalance_history is empty: the balancer never ran")
    if s["face_moves"] < 1:
        fail("the balancer never moved a face")
    if s["handed_over_particles"] <= 0:
        fail("faces moved but no particle changed owner")
    if s["migrated_particles"] <= 0:
        fail("no particle crossed a face by moving")
    if s["device_particles"] == s0["device_particles"]:
        fail("per-device counts did not change")
    if not s["imbalance"] < s0["imbalance"]:
        fail(f"imbalance {s['imbalance']:.3f} is not below the initial {s0['imbalance']:.3f}")
    spate.compare(final_checkpoint(single), final_checkpoint(out))
    print(f"PASS: {args.steps} steps on {split[0]}x{split[1]}: {s['face_moves']} face moves, "
          f"{s['migrated_particles']} crossings, imbalance {s0['imbalance']:.2f} -> {s['imbalance']:.2f}, same answer as 1x1")


def cmd_bad_input(args):
    """Refusals: exit code 2 and a message naming the problem."""
    spate = Spate(args)
    split = args.splits[0]
    tests = []
    tests.append(("devices_zero", (split[0], 0), [], "--devices 0"))
    tests.append(("too_many_slabs", (split[0], args.too_many), [], "at least 3 cells"))
    if args.mismatched_set:
        # A checkpoint of the case at another resolution (another particle count) must be refused.
        other = Spate(args)
        other.sets += [item for s in args.mismatched_set for item in ("--set", s)]
        other_out, _ = other.run("bad_other_resolution", (1, 1), ["--steps", "1"])
        tests.append(("mismatched_restart", split, ["--restart", str(final_checkpoint(other_out))], "checkpoint holds"))
    garbage = spate.work / "not_a_checkpoint.h5"
    garbage.write_text("not HDF5\n")
    tests.append(("garbage_restart", split, ["--restart", str(garbage)], str(garbage.name)))
    for name, sp, extra, needle in tests:
        out, p = spate.run("bad_" + name, sp, ["--steps", "1", *extra], expect=2)
        if needle not in p.stderr:
            print(p.stderr)
            fail(f"{name}: the message does not mention '{needle}'")
        # One summary.json (rank 0's) says so, and nothing else is written.
        s = summary(out)
        if s["exit_code"] != 2 or s["exit_status"] != "bad_input" or sorted(os.listdir(out)) != ["summary.json"]:
            fail(f"{name}: {out} holds {sorted(os.listdir(out))}, summary {s['exit_status']} {s['exit_code']}")
        print(f"  {name}: exit 2: {p.stderr.strip().splitlines()[0]}")
    print("PASS: bad splits and restart files are refused with exit code 2")


def cmd_rank_failure(args):
    """A failure on one rank (its snapshot piece cannot be written) ends every rank with a message
    and a non-zero exit, instead of leaving the others waiting."""
    spate = Spate(args)
    split = args.splits[0]
    ranks, devices = split
    victim = ranks * devices - 1  # a slab on the last rank
    out = spate.work / "rank_failure"
    shutil.rmtree(out, ignore_errors=True)
    (out / "snapshots" / "step_00000000" / f"slab_{victim}.vtp").mkdir(parents=True)
    cmd = spate.command(split, ["--out", str(out), "--steps", "20"])
    print("$ " + " ".join(cmd), flush=True)
    begin = time.monotonic()
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=120, env=mpi_env())
    except subprocess.TimeoutExpired:
        fail("the other ranks hung after one rank failed")
    print(f"  exit {p.returncode} in {time.monotonic() - begin:.1f} s")
    print("  " + "\n  ".join(p.stderr.strip().splitlines()[:3]))
    if p.returncode == 0:
        fail("a run with a failing rank exited 0")
    if f"slab_{victim}.vtp" not in p.stderr or f"rank {ranks - 1}" not in p.stderr:
        fail("the message does not name the failing rank and its file")
    print(f"PASS: a failure on rank {ranks - 1} ended all {ranks} ranks with exit {p.returncode}")


def cmd_unstable(args):
    """A run that goes unstable is known to every rank (collective check): all end with exit code 3,
    rank 0 writes the summary, and every slab writes its piece of the diagnostic snapshot."""
    spate = Spate(args)
    split = args.splits[0]
    out, p = spate.run("unstable", split, ["--steps", str(args.steps)], expect=3)
    s = summary(out)
    if s["exit_status"] != "unstable" or "went unstable" not in p.stderr:
        fail(f"exit_status {s['exit_status']}; stderr: {p.stderr}")
    pieces = list((out / "diagnostic").glob("step_*/slab_*.vtp"))
    if len(pieces) != split[0] * split[1]:
        fail(f"{len(pieces)} diagnostic pieces for {split[0] * split[1]} slabs")
    print(f"PASS: unstable run on {split[0]}x{split[1]} ended with exit 3 on every rank, {len(pieces)} diagnostic pieces")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("mode", choices=["splits", "restart", "balance", "bad-input", "rank-failure", "unstable"])
    ap.add_argument("--spate", required=True)
    ap.add_argument("--case", required=True)
    ap.add_argument("--work", required=True, help="folder for the runs")
    ap.add_argument("--set", action="append", default=[], help="case override passed to every run")
    ap.add_argument("--steps", type=int, default=200)
    ap.add_argument("--splits", type=lambda t: [parse_split(v) for v in t.split(",")], default=[(1, 1)])
    ap.add_argument("--mpiexec", default="")
    ap.add_argument("--mpiexec-args", default="")
    ap.add_argument("--fresh", action="store_true", help="splits: empty the work folder first")
    ap.add_argument("--expect-migration", action="store_true", help="splits: particles must cross faces in every multi-slab run")
    ap.add_argument("--pvbatch", default="", help="check that ParaView opens the last split's snapshots as one dataset")
    ap.add_argument("--too-many", type=int, default=64, help="a device count with fewer than 3 cells per slab")
    ap.add_argument("--expect-removed", action="store_true", help="splits, restart: fluid leaves through open sides")
    ap.add_argument("--mismatched-set", action="append", default=[],
                    help="case override that makes a checkpoint which does not fit the case (bad-input)")
    args = ap.parse_args()
    {"splits": cmd_splits, "restart": cmd_restart, "balance": cmd_balance, "bad-input": cmd_bad_input,
     "rank-failure": cmd_rank_failure, "unstable": cmd_unstable}[args.mode](args)


if __name__ == "__main__":
    main()
