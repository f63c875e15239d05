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


if __name__ == "__main__":
    sys.exit(main(TESTS))
