#!/usr/bin/env python3
"""In-situ robustness (ctest label `robustness`): nothing a pipeline does loses the run.

Each scenario runs `spate run` on the 2D dam break with pipelines this test writes itself, and
checks from the outputs (exit code, summary.json, insitu.json, images, checkpoints) that the
simulation went on, or ended cleanly, whatever the pipeline did. Every wait is bounded; children
are killed on any exit.

Usage: robustness.py SPATE SOURCE_DIR WORK_DIR SCENARIO
"""
import json
import os
import shutil
import signal
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from proc_sockets import listening  # noqa: E402

spate, src, work, scenario = sys.argv[1:5]
case = os.path.join(src, "cases", "dam_break_2d.yaml")
quick = ["--set", "output.interval=0", "--set", "probes=[]", "--checkpoint-every", "0", "--threads", "2"]
children = []


def fail(msg):
    print("FAIL:", msg, flush=True)
    for p in children:
        if p.poll() is None:
            os.killpg(p.pid, signal.SIGKILL)
    sys.exit(1)


def spate_run(name, args, seconds=240, sample=None):
    """Runs spate; returns (exit code, output folder, stderr). sample(pid) is called while it runs."""
    out = os.path.join(work, name)
    shutil.rmtree(out, ignore_errors=True)
    err_path = out + ".err"
    with open(out + ".out", "w") as so, open(err_path, "w") as se:
        p = subprocess.Popen([spate, "run", case, "--out", out] + quick + args, stdout=so, stderr=se,
                             start_new_session=True)
        children.append(p)
        deadline = time.time() + seconds
        while p.poll() is None:
            if time.time() > deadline:
                fail(f"{name}: spate still running after {seconds} s (a hang)")
            if sample:
                sample(p.pid)
            time.sleep(0.05)
    return p.returncode, out, open(err_path).read()


def summary(out):
    path = os.path.join(out, "summary.json")
    if not os.path.exists(path):
        fail(f"{out}: no summary.json")
    return json.load(open(path))


def no_listening_socket():
    """Neither spate nor any child (the in-situ helper, OpenMPI's daemons) listens, with a
    pipeline and with --live (connecting out to a port where nobody listens)."""
    for name, args in (("pipeline", ["--pipeline", os.path.join(src, "pipelines", "particles.py")]),
                       ("live", ["--live", "localhost:9"])):
        seen, commands = set(), set()

        def sample(pid):
            seen.update(listening(pid))

        code, out, err = spate_run("sockets_" + name, args + ["--steps", "60", "--insitu-every", "20"], sample=sample)
        if code != 0:
            fail(f"{name}: exit {code}:\n{err}")
        if seen:
            fail(f"{name}: listening sockets in spate's process tree: {sorted(seen)}")
        print(f"{name}: no listening socket in spate's process tree (sampled every 50 ms)")


scenarios = {f.__name__: f for f in (no_listening_socket,)}
if scenario not in scenarios:
    fail(f"unknown scenario {scenario}; known: {', '.join(scenarios)}")
os.makedirs(work, exist_ok=True)
try:
    scenarios[scenario]()
    print(f"{scenario}: OK")
finally:
    for p in children:
        if p.poll() is None:
            os.killpg(p.pid, signal.SIGKILL)
