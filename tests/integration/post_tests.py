#!/usr/bin/env python3
"""Integration tests of what users do around and after a run: `--version` and the provenance in
summary.json, the log format, probe CSV headers, thin-feature warnings, checkpoint retention,
`spate post` and `spate plot`. Same command line as cli_tests.py (one CTest test per name):

    post_tests.py --spate build/bin/spate --cases tests/cases --shipped cases --work DIR NAME
"""
import datetime
import hashlib
import json
import os
import re
import socket
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cli_tests import Env, check, main  # noqa: E402  (the shared harness)

TESTS = {}


def test(fn):
    TESTS[fn.__name__] = fn
    return fn


TIMESTAMP = re.compile(r"^\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\.\d{3}Z spate: ")


def source_dir(env):
    return os.path.dirname(env.shipped)


def summary(out):
    with open(os.path.join(out, "summary.json")) as f:
        return json.load(f)


# ---- provenance and the log ---------------------------------------------------------------------

@test
def version_and_provenance(env):
    p = env.run("--version")
    check(p.returncode == 0, f"--version: exit {p.returncode}")
    m = re.fullmatch(r"spate (\d+\.\d+\.\d+) \(commit ([0-9a-f]{12}(?:-dirty)?|unknown)\)\n", p.stdout)
    check(m, f"--version printed {p.stdout!r}, expected 'spate X.Y.Z (commit HASH)'")
    version, commit = m.group(1), m.group(2)
    src = source_dir(env)
    if commit != "unknown":
        # The commit the program was built from is one of the repository's (not necessarily HEAD:
        # a commit may have been made since the build).
        known = subprocess.run(["git", "-C", src, "cat-file", "-e", commit.split("-")[0] + "^{commit}"],
                               capture_output=True)
        check(known.returncode == 0, f"commit {commit} is not in the repository at {src}")
    elif subprocess.run(["git", "-C", src, "rev-parse", "HEAD"], capture_output=True).returncode == 0:
        check(False, "built inside a git checkout, yet the commit is 'unknown'")

    out = env.path("out")
    argv = ["run", env.tiny, "--steps", "2", "--out", out, "--set", "time.end=1", "--quiet"]
    before = datetime.datetime.now(datetime.timezone.utc).replace(microsecond=0)
    p = env.run(*argv)
    after = datetime.datetime.now(datetime.timezone.utc)
    check(p.returncode == 0, f"run: exit {p.returncode}")
    s = summary(out)
    check(s["version"] == version and s["commit"] == commit, f"summary version/commit {s['version']}/{s['commit']}")
    check(s["command_line"] == [env.spate] + argv, f"command_line {s['command_line']}")
    with open(env.tiny, "rb") as f:
        digest = hashlib.sha256(f.read()).hexdigest()
    check(s["case_file_sha256"] == digest, f"case_file_sha256 {s['case_file_sha256']}, sha256sum says {digest}")
    check(s["host"] == socket.gethostname(), f"host {s['host']}")
    times = []
    for key in ("start_time", "end_time"):
        check(re.fullmatch(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ", s[key]), f"{key} {s[key]!r} is not ISO 8601 UTC")
        times.append(datetime.datetime.strptime(s[key], "%Y-%m-%dT%H:%M:%SZ").replace(tzinfo=datetime.timezone.utc))
    check(before <= times[0] <= times[1] <= after, f"start/end {times} not within the run ({before} .. {after})")


@test
def log_levels_and_format(env):
    """Off a terminal every line is timestamped and plain; --log-level filters."""
    out = env.path("out")
    p = env.run("run", env.tiny, "--steps", "2", "--out", out, "--log-level", "debug")
    check(p.returncode == 0, f"exit {p.returncode}")
    lines = [l for l in p.stdout.splitlines() if l.strip()]
    check(lines and all(TIMESTAMP.match(l) for l in lines), "a stdout line without the timestamp prefix")
    check(any("debug: checkpoint of step 2" in l for l in lines), "--log-level debug: no debug line about the checkpoint")
    check(any("tiny_2d done" in l for l in lines), "no info line at the end of the run")
    check("\x1b" not in p.stdout + p.stderr, "escape codes in the output")
    p = env.run("run", env.tiny, "--steps", "2", "--out", out, "--log-level", "warning")
    check(p.returncode == 0 and p.stdout.strip() == "", f"--log-level warning still printed: {p.stdout!r}")
    p = env.run("--log-level", "error", "run", env.tiny, "--steps", "2", "--out", out)
    check(p.returncode == 0 and p.stdout.strip() == "", "--log-level before the command is not honoured")
    p = env.run("run", env.tiny, "--steps", "2", "--out", out, "--log-level", "loud")
    check(p.returncode == 2 and "--log-level" in p.stderr, "a bad --log-level is not bad input")


# ---- thin features ------------------------------------------------------------------------------

@test
def thin_feature_warning(env):
    """The column case's 1 cm wet bed at dp = 0.015 (0.67 layers): info and run say so, with the dp
    that resolves it; a resolved case says nothing."""
    column = os.path.join(env.shipped, "dam_break_column_3d.yaml")
    needle = "wet_bed: the wet bed is 0.01 m deep: 0.67 particle layers at dp = 0.015 m"
    p = env.run("info", column, "--set", "dp=0.015")
    check(p.returncode == 0 and needle in p.stderr and "dp <= 0.00333 m resolves it" in p.stderr,
          "info: no thin-feature warning on stderr")
    check("spate: warning:" in p.stderr, "info: the warning is not a warning line")
    p = env.run("info", column, "--set", "dp=0.015", "--json")
    w = json.loads(p.stdout)["warnings"]
    check(len(w) == 1 and w[0]["key"] == "wet_bed" and abs(w[0]["resolving_dp"] - 0.01 / 3) < 1e-9, f"info --json warnings {w}")
    out = env.path("out")
    p = env.run("run", column, "--set", "dp=0.015", "--steps", "0", "--out", out, "--quiet")
    check(p.returncode == 0 and needle in p.stderr, "run: no thin-feature warning")
    s = summary(out)
    check(len(s["warnings"]) == 1 and needle in s["warnings"][0], f"summary.json warnings {s['warnings']}")
    p = env.run("info", column, "--set", "dp=0.015", "--set", "wet_bed=0")
    check(p.returncode == 0 and "warning" not in p.stderr, "a case without thin features warns")


# ---- checkpoints --------------------------------------------------------------------------------

@test
def checkpoint_retention(env):
    """--checkpoint-keep-last K keeps the newest K, --checkpoint-keep-every N every Nth for good;
    each checkpoint has its XDMF sidecar and loses it with it. The case keys do the same."""
    out = env.path("out")
    p = env.run("run", env.tiny, "--steps", "23", "--checkpoint-every", "2", "--checkpoint-keep-last", "3",
                "--checkpoint-keep-every", "4", "--out", out, "--quiet")
    check(p.returncode == 0, f"exit {p.returncode}")
    kept = sorted(os.listdir(os.path.join(out, "checkpoints")))
    steps = [8, 16, 20, 22, 23]  # every 4th of the checkpoints at 2, 4, ..., 22, the newest 3, the final one
    expected = sorted([f"checkpoint_step_{s:08d}.h5" for s in steps] + [f"checkpoint_step_{s:08d}.xmf2" for s in steps])
    check(kept == expected, f"kept {kept}, expected {expected}")
    out = env.path("out_case")
    p = env.run("run", env.tiny, "--steps", "7", "--set", "output.checkpoint_every=1", "--set", "output.checkpoint_keep_last=0",
                "--out", out, "--quiet")
    check(p.returncode == 0 and len([f for f in os.listdir(os.path.join(out, "checkpoints")) if f.endswith(".h5")]) == 7,
          "output.checkpoint_keep_last=0 does not keep every checkpoint")
    out = env.path("out_default")
    p = env.run("run", env.tiny, "--steps", "7", "--checkpoint-every", "1", "--out", out, "--quiet")
    check(sorted(os.listdir(os.path.join(out, "checkpoints"))) ==
          ["checkpoint_step_00000006.h5", "checkpoint_step_00000006.xmf2", "checkpoint_step_00000007.h5", "checkpoint_step_00000007.xmf2"],
          "by default the two newest are kept")
    p = env.run("run", env.tiny, "--steps", "1", "--checkpoint-keep-last", "-1", "--out", env.path("bad"), "--quiet")
    check(p.returncode == 2 and "--checkpoint-keep-last" in p.stderr, "a negative --checkpoint-keep-last is not bad input")


if __name__ == "__main__":
    sys.exit(main(TESTS))
