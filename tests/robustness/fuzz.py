#!/usr/bin/env python3
"""Fuzzing the real `spate` program with mutated case files and checkpoints. Every mutant must end
with exit 0 (a mutant that is still valid) or 2 (bad input, one message): no signal, no timeout,
no exit 4 (internal error), no HDF5 diagnostics, and every run leaves a summary.json with its exit
code. Runs take no step (--steps 0: generation, the halo, the first rates, outputs and the final
checkpoint all run), so that no mutant can be legitimately unstable. Mutants that fail are kept in the work folder for reproduction.

    fuzz.py --spate build/bin/spate --cases tests/cases --shipped cases --work DIR [--cases-count N]
            [--checkpoints-count N] [--seed S] [--jobs J]
"""
import argparse
import concurrent.futures
import json
import os
import random
import re
import resource
import shutil
import subprocess
import sys
import time

import h5py
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import checkpoint_tools as ck  # noqa: E402

TIMEOUT = 60  # seconds per run; a hang fails
# An address-space limit for every run: a mutant asking for a huge particle set must be refused by
# the memory estimate (exit 2), not allowed to fill the machine. SPATE_FUZZ_ADDRESS_SPACE=0 lifts
# it (an ASan build reserves terabytes of address space), with --max-run-memory in its place.
ADDRESS_SPACE = int(os.environ.get("SPATE_FUZZ_ADDRESS_SPACE", str(3 << 30)))

SPECIAL = ["0", "-1", "1e300", "-1e300", "1e-300", ".nan", ".inf", "-.inf", "nan", "1e400", "", "~", "abc", "[]", "{}",
           "[1, 2, 3, 4]", "[0, 0]", "true", "2147483648", "-2147483649", "0x10", "'3'", "!!binary AAAA", "*x", "&a 1",
           "[.nan, .nan]", "[1e300, 1e300]", "[-1, -1]", "1e-9", "100000"]
KEYS = ["name", "dp", "dimensions", "tank", "size", "origin", "fluid_blocks", "min", "max", "time", "end", "dt", "probes",
        "solids", "wet_bed", "headroom", "interval", "probe_interval", "checkpoint_every", "gravity", "density", "mode",
        "smoothing_ratio", "kernel", "wall_layers", "periodic", "open_top", "insitu", "balance_every", "max_removed_fraction"]


def mutate_case(text, rng):
    lines = text.splitlines()
    for _ in range(rng.randint(1, 3)):
        op = rng.randrange(10)
        k = rng.randrange(len(lines)) if lines else 0
        if not lines:
            lines = ["{"]
        elif op == 0:  # a value replaced by a special one
            line = lines[k]
            if ":" in line:
                key = line.split(":", 1)[0]
                lines[k] = f"{key}: {rng.choice(SPECIAL)}"
        elif op == 1:  # a number scaled, negated or made tiny
            words = lines[k].replace(",", " , ").replace("]", " ] ").replace("[", " [ ").split()
            idx = [i for i, w in enumerate(words) if w.replace(".", "", 1).replace("-", "", 1).replace("e", "", 1).isdigit()]
            if idx:
                i = rng.choice(idx)
                words[i] = rng.choice([str(float(words[i]) * rng.choice([1e-6, 1e-3, 0.5, 2, 1e3, 1e6, -1])), "0", "1e-300"])
                lines[k] = " ".join(words).replace(" , ", ", ").replace("[ ", "[").replace(" ]", "]")
        elif op == 2:
            del lines[k]
        elif op == 3:
            lines.insert(k, lines[rng.randrange(len(lines))])
        elif op == 4:
            j = rng.randrange(len(lines))
            lines[k], lines[j] = lines[j], lines[k]
        elif op == 5:  # indentation changed
            lines[k] = " " * rng.choice([0, 1, 2, 3, 4, 8]) + lines[k].lstrip()
        elif op == 6:
            lines.insert(k, f"{rng.choice(KEYS)}: {rng.choice(SPECIAL)}")
        elif op == 7:  # random bytes
            pos = rng.randrange(len(lines[k]) + 1)
            junk = "".join(chr(rng.choice([0x7f, 0x1b, ord(":"), ord("{"), ord("'"), ord("&"), ord("*"), 0xe9, 0x2603])) for _ in range(3))
            lines[k] = lines[k][:pos] + junk + lines[k][pos:]
        elif op == 8:
            lines.insert(k, rng.choice(["---", "...", "%YAML 1.2", "? complex key", "- item", "name: ../../x", "  - name: /tmp/p"]))
        else:  # truncated
            lines = lines[:k]
    return "\n".join(lines) + ("\n" if rng.random() < 0.8 else "")


def mutate_checkpoint(source, target, rng):
    shutil.copyfile(source, target)
    size = os.path.getsize(target)
    op = rng.randrange(8)
    if op == 0:  # bits flipped anywhere
        for _ in range(rng.randint(1, 8)):
            ck.flip_byte(target, rng.randrange(size), 1 << rng.randrange(8))
    elif op == 1:  # a run of random bytes
        at = rng.randrange(size)
        with open(target, "r+b") as f:
            f.seek(at)
            f.write(bytes(rng.randrange(256) for _ in range(rng.randint(1, 64))))
    elif op == 2:  # truncated or extended
        with open(target, "r+b") as f:
            f.truncate(rng.randrange(size) if rng.random() < 0.7 else size + rng.randint(1, 5000))
    else:  # structural, through HDF5
        with h5py.File(target, "r+") as f:
            names = list(f["particles"].keys())
            what = rng.randrange(7)
            if what == 0:
                attr = rng.choice(list(f.attrs.keys()))
                del f.attrs[attr]
                f.attrs[attr] = rng.choice([np.int64(rng.randint(-10, 10**9)), np.float64(rng.choice([np.nan, np.inf, -1.0, 0.0, 1e300])),
                                            "text", np.arange(rng.randint(0, 50)), np.bytes_(b"x" * rng.randint(0, 100))])
            elif what == 1:
                name = rng.choice(names)
                d = f["particles/" + name][...]
                new = rng.choice([d[: rng.randrange(len(d) + 1)], np.concatenate([d, d[:5]]), d.astype("f8"), d.astype("i2"),
                                  d.reshape(-1, 1), np.array([], dtype=d.dtype)])
                ck.replace_dataset(f, name, new, fletcher32=rng.random() < 0.7)
            elif what == 2:
                name = rng.choice(names)
                d = f["particles/" + name][...]
                i = rng.randrange(len(d))
                if d.dtype.kind == "f":
                    d[i] = rng.choice([np.nan, np.inf, -np.inf, 1e30, -1e30, 0.0, 1e-40])
                else:
                    d[i] = rng.randrange(np.iinfo(d.dtype).max + 1)
                ck.replace_dataset(f, name, d)
            elif what == 3:
                del f["particles/" + rng.choice(names)]
            elif what == 4:
                ck.set_text(f, "steering_log", rng.choice(["1 0 gravity 0 -1e30 0\n", "1 0 gravity 1\n", "x\n", "1 0 stop 1e400\n",
                                                           "1 0 insitu_every 0.5\n", "1 nan viscosity 1\n", "-1 0 stop 1\n"]))
                if rng.random() < 0.8:
                    ck.resign(f)
            elif what == 5:
                text = ck.text_attr(f, "case_yaml")
                ck.set_text(f, "case_yaml", mutate_case(text, rng))
                if rng.random() < 0.8:
                    ck.resign(f)
            else:
                del f["particles"]
                f.create_group("particles") if rng.random() < 0.5 else f.create_dataset("particles", data=np.zeros(3))


def run(spate, argv, cwd):
    def limits():
        resource.setrlimit(resource.RLIMIT_AS, (ADDRESS_SPACE, ADDRESS_SPACE))
    env = dict(os.environ, OMP_NUM_THREADS="1")
    try:
        p = subprocess.run([spate, *argv], capture_output=True, text=True, timeout=TIMEOUT, cwd=cwd, env=env,
                           preexec_fn=limits if ADDRESS_SPACE > 0 else None)
    except subprocess.TimeoutExpired:
        return None, "", f"no answer after {TIMEOUT} s"
    return p.returncode, p.stdout, p.stderr


def verdict(code, stderr):
    if code is None:
        return stderr
    if code < 0:
        return f"killed by signal {-code}"
    if code not in (0, 2):
        return f"exit {code}"
    if "HDF5-DIAG" in stderr:
        return "HDF5 printed its own diagnostics"
    if code == 2 and not re.match(r"^(\d{4}-\d\d-\d\dT[\d:.]+Z )?spate: error: ", stderr.strip()):
        return "exit 2 without a 'spate: error:' message"
    return None


def summary_verdict(argv, code):
    """A run (its --out usable) leaves a summary.json with its exit code, refused or not."""
    if argv[0] != "run" or code is None or code < 0:
        return None
    path = os.path.join(argv[argv.index("--out") + 1], "summary.json")
    try:
        with open(path) as f:
            s = json.load(f)
    except (OSError, ValueError) as e:
        return f"no readable summary.json after exit {code}: {e}"
    if s.get("exit_code") != code:
        return f"summary.json says exit {s.get('exit_code')}, the process ended with {code}"
    return None


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--spate", required=True)
    ap.add_argument("--cases", required=True)
    ap.add_argument("--shipped", required=True)
    ap.add_argument("--work", required=True)
    ap.add_argument("--cases-count", type=int, default=150)
    ap.add_argument("--checkpoints-count", type=int, default=75)
    ap.add_argument("--seed", type=int, default=int(os.environ.get("SPATE_FUZZ_SEED", "14")))
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--max-run-memory", type=int, default=0,
                    help="run only case mutants whose `spate info` estimate is below this many bytes (0: all)")
    args = ap.parse_args()
    spate = os.path.abspath(args.spate)
    work = os.path.abspath(args.work)
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    rng = random.Random(args.seed)
    seeds = [os.path.join(args.cases, "tiny_2d.yaml"), os.path.join(args.cases, "spill_2d.yaml"),
             os.path.join(args.shipped, "dam_break_2d.yaml"), os.path.join(args.shipped, "hydrostatic_2d.yaml")]
    texts = [open(p).read() for p in seeds]
    # A seed checkpoint (tiny case, 2 steps, a steering change on the way).
    base = os.path.join(work, "base")
    log = os.path.join(work, "base.log")
    with open(log, "w") as f:
        f.write("1 0.0002 viscosity 0.002\n")
    code, _, err = run(spate, ["run", seeds[0], "--steps", "2", "--steering-log", log, "--out", base, "--quiet"], work)
    if code != 0:
        print(f"FAIL: the seed checkpoint: exit {code}: {err}")
        return 1
    source = os.path.join(base, "checkpoints", "checkpoint_step_00000002.h5")

    jobs = []
    for k in range(args.cases_count):
        folder = os.path.join(work, f"case_{k:03d}")
        os.makedirs(folder)
        path = os.path.join(folder, "case.yaml")
        with open(path, "w", errors="surrogateescape") as f:
            f.write(mutate_case(rng.choice(texts), rng))
        argv = ["info", path] if k % 3 == 2 else ["run", path, "--steps", "0", "--out", os.path.join(folder, "out"), "--quiet"]
        if args.max_run_memory and argv[0] == "run":
            code, out, _ = run(spate, ["info", path, "--json"], folder)
            try:
                if code == 0 and json.loads(out)["run_memory_bytes"] > args.max_run_memory:
                    argv = ["info", path]
            except (ValueError, KeyError):
                pass
        jobs.append((f"case_{k:03d}", folder, argv))
    for k in range(args.checkpoints_count):
        folder = os.path.join(work, f"checkpoint_{k:03d}")
        os.makedirs(folder)
        path = os.path.join(folder, "mutant.h5")
        try:
            mutate_checkpoint(source, path, rng)
        except (OSError, ValueError, KeyError, TypeError) as e:  # h5py refused the edit: a byte-level mutant instead
            shutil.copyfile(source, path)
            ck.flip_byte(path, rng.randrange(os.path.getsize(path)))
            print(f"  checkpoint_{k:03d}: h5py edit failed ({type(e).__name__}), flipped a byte instead")
        argv = (["compare", path, path] if k % 2 == 0 else
                ["run", seeds[0], "--restart", path, "--steps", "0", "--out", os.path.join(folder, "out"), "--quiet"])
        jobs.append((f"checkpoint_{k:03d}", folder, argv))

    begin = time.monotonic()
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    failures, codes = [], {}
    with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as pool:
        futures = {pool.submit(run, spate, argv, folder): (name, folder, argv) for name, folder, argv in jobs}
        for fut in concurrent.futures.as_completed(futures):
            name, folder, argv = futures[fut]
            code, out, err = fut.result()
            codes[code] = codes.get(code, 0) + 1
            problem = verdict(code, err) or summary_verdict(argv, code)
            if problem:
                failures.append(name)
                print(f"FAIL {name}: {problem}\n  $ spate {' '.join(argv)}\n  " + "\n  ".join((out + err).strip().splitlines()[:10]))
            else:
                shutil.rmtree(folder, ignore_errors=True)
    seconds = time.monotonic() - begin
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    # The CPU time of the spate processes: what the fuzz costs whatever else the machine is doing
    # (the wall-clock time is about this over the jobs on an idle machine).
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    print(f"{len(jobs)} mutants ({args.cases_count} case files, {args.checkpoints_count} checkpoints, seed {args.seed}) in {seconds:.0f} s"
          f" ({cpu:.0f} CPU-s of spate, {args.jobs} at a time); exit codes {dict(sorted(codes.items(), key=lambda kv: str(kv[0])))}")
    if failures:
        print(f"FAIL: {len(failures)} mutants: {', '.join(sorted(failures))} (kept in {work})")
        return 1
    print("PASS")
    return 0


if __name__ == "__main__":
    sys.exit(main())
