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


# ---- spate post ---------------------------------------------------------------------------------

def probe_rows(folder):
    """{probe: (header, {step: row})} of a probes/ folder, rows as the exact text of the file."""
    out = {}
    for f in sorted(os.listdir(folder)):
        lines = open(os.path.join(folder, f)).read().splitlines()
        out[f[:-4]] = (lines[0], {line.split(",")[1]: line for line in lines[1:]})
    return out


def check_reproduced(run_probes, post_probes, saved_steps, what):
    """Every row spate post wrote is, to the last digit, the run's row of that step; one per saved step."""
    run, post = probe_rows(run_probes), probe_rows(post_probes)
    check(sorted(post) == sorted(run), f"{what}: probes {sorted(post)}, the run has {sorted(run)}")
    for name, (header, rows) in post.items():
        check(header == run[name][0], f"{what}: {name}: header {header!r}, the run's {run[name][0]!r}")
        check(sorted(rows, key=int) == saved_steps, f"{what}: {name}: steps {sorted(rows, key=int)}, saved {saved_steps}")
        for step, row in rows.items():
            check(row == run[name][1].get(step), f"{what}: {name} at step {step}: post {row!r}, run {run[name][1].get(step)!r}")


@test
def post_reproduces_probes_at_every_saved_step(env):
    """spate post on the snapshots and on the checkpoints of a finished run (2 devices) writes, at
    every saved step, exactly the values the run's probes wrote; the run's probes are the same with
    1 and 2 devices (ghosts refreshed before sampling)."""
    case = os.path.join(env.cases, "probes_2d.yaml")
    runs = {}
    for devices in ("1", "2"):
        out = env.path(f"run{devices}")
        p = env.run("run", case, "--devices", devices, "--out", out, "--quiet")
        check(p.returncode == 0, f"run --devices {devices}: exit {p.returncode}")
        runs[devices] = out
    check(probe_rows(os.path.join(runs["1"], "probes")) == probe_rows(os.path.join(runs["2"], "probes")),
          "the run's probe files differ between 1 and 2 devices")
    out = runs["2"]
    snapshots = sorted(int(f[5:13]) for f in os.listdir(os.path.join(out, "snapshots")) if f.endswith(".vtm"))
    checkpoints = sorted(int(f[16:24]) for f in os.listdir(os.path.join(out, "checkpoints")) if f.endswith(".h5"))
    check(len(snapshots) >= 6 and len(checkpoints) >= 3, f"saved steps: snapshots {snapshots}, checkpoints {checkpoints}")
    p = env.run("post", out)
    check(p.returncode == 0, f"post: exit {p.returncode}")
    check_reproduced(os.path.join(out, "probes"), os.path.join(out, "post", "probes"), [str(s) for s in snapshots], "snapshots")
    p = env.run("post", out, "--from", "checkpoints", "--out", env.path("from_checkpoints"))
    check(p.returncode == 0, f"post --from checkpoints: exit {p.returncode}")
    check_reproduced(os.path.join(out, "probes"), env.path("from_checkpoints", "probes"), [str(s) for s in checkpoints], "checkpoints")
    # The values are not trivial: the water at the foot of the column is moving.
    u = [float(r.split(",")[2]) for r in probe_rows(os.path.join(out, "probes"))["u"][1].values()]
    check(max(u) > 0.2, f"the velocity probe reads at most {max(u)} m/s")


@test
def post_writes_body_probes(env):
    """A floating solid's body probe (issue 32): spate post writes, from the snapshots (their field
    data holds the bodies' state) and from the checkpoints, exactly the run's rows."""
    out = env.path("run")
    p = env.run("run", os.path.join(env.shipped, "floating_box_2d.yaml"), "--set", "dp=0.02", "--set", "output.interval=0.02",
                "--set", "output.probe_interval=0", "--until", "0.1", "--checkpoint-every", "150", "--out", out, "--quiet")
    check(p.returncode == 0, f"run: exit {p.returncode}: {p.stderr[-500:]}")
    snapshots = sorted(int(f[5:13]) for f in os.listdir(os.path.join(out, "snapshots")) if f.endswith(".vtm"))
    checkpoints = sorted(int(f[16:24]) for f in os.listdir(os.path.join(out, "checkpoints")) if f.endswith(".h5"))
    p = env.run("post", out)
    check(p.returncode == 0, f"post: exit {p.returncode}: {p.stderr[-500:]}")
    run = probe_rows(os.path.join(out, "probes"))
    for where, steps in ((os.path.join(out, "post", "probes"), snapshots), (env.path("from_checkpoints", "probes"), checkpoints)):
        if where.startswith(env.path("from_checkpoints")):
            p = env.run("post", out, "--from", "checkpoints", "--out", env.path("from_checkpoints"))
            check(p.returncode == 0, f"post --from checkpoints: exit {p.returncode}")
        post = probe_rows(where)
        rows = post["box"][1]
        check(sorted(rows, key=int) == [str(s) for s in steps], f"{where}: box at steps {sorted(rows, key=int)}, saved {steps}")
        for step, row in rows.items():
            check("nan" not in row and row == run["box"][1].get(step), f"{where}: box at step {step}: post {row!r}, run {run['box'][1].get(step)!r}")
    # The box moves: its height changes over the run.
    heights = {float(r.split(",")[3]) for r in run["box"][1].values()}
    check(max(heights) - min(heights) > 1e-3, f"the box's centre stays between {min(heights)} and {max(heights)} m")


@test
def post_probes_from_the_command_line(env):
    """--probe defines probes after the run; one that repeats a case probe gives the run's values."""
    out = env.path("run")
    p = env.run("run", os.path.join(env.cases, "probes_2d.yaml"), "--out", out, "--until", "0.01", "--quiet")
    check(p.returncode == 0, f"run: exit {p.returncode}")
    p = env.run("post", out, "--probe", "{name: again, type: pressure, position: [0.002, 0.01]}",
                "--probe", "{name: middle, type: velocity, position: [0.02, 0.05]}", "--out", env.path("post"))
    check(p.returncode == 0, f"post --probe: exit {p.returncode}")
    post = probe_rows(env.path("post", "probes"))
    run = probe_rows(os.path.join(out, "probes"))
    check(sorted(post) == ["again", "middle"], f"post wrote {sorted(post)}")
    check(post["again"][0] == "time[s],step,pressure[Pa]" and post["middle"][0] == "time[s],step,vx[m/s],vy[m/s]",
          f"headers {post['again'][0]!r}, {post['middle'][0]!r}")
    for step, row in post["again"][1].items():
        check(row == run["wall_pressure"][1][step], f"step {step}: {row!r} vs the run's wall_pressure {run['wall_pressure'][1][step]!r}")
    # Bad input: a probe the case loader rejects, a run folder that is not one, a step never saved.
    p = env.run("post", out, "--probe", "{name: x, type: pressure, position: [0.1]}")
    check(p.returncode == 2 and "--probe" in p.stderr and "probes[0].position" in p.stderr, "a bad --probe is not bad input")
    p = env.run("post", env.path("nowhere"))
    check(p.returncode == 2 and "no such run folder" in p.stderr, "a missing run folder")
    p = env.run("post", out, "--step", "7")
    check(p.returncode == 2 and "--step 7" in p.stderr, "a step that was not saved")
    p = env.run("post", out, "--from", "nothing")
    check(p.returncode == 2 and "--from" in p.stderr, "a bad --from")


@test
def post_replays_steered_wall_motion(env):
    """A run whose tank motion was steered (its steering.log): spate post puts the walls, and the
    height gauge that rides with the tank, where the run had them, so it writes the run's rows
    exactly; without the log the rows differ (the test can fail)."""
    case = os.path.join(env.shipped, "sloshing_2d.yaml")
    log = env.path("steer.log")
    with open(log, "w") as f:
        f.write("# amplitude x2 from step 20\n20 0.0 motion_amplitude 0 2\n")
    out = env.path("run")
    p = env.run("run", case, "--out", out, "--quiet", "--steering-log", log, "--set", "dp=0.02", "--set", "time.end=0.4",
                "--set", "tank.motion.period=0.4", "--set", "tank.motion.ramp=0", "--set", "output.interval=0.05",
                "--set", "output.probe_interval=0.05", "--set", "output.checkpoint_every=0")
    check(p.returncode == 0, f"run with a steering log: exit {p.returncode}: {p.stderr[-400:]}")
    check("motion_amplitude" in open(os.path.join(out, "steering.log")).read(), "the run's steering.log has no motion change")
    snapshots = sorted(int(f[5:13]) for f in os.listdir(os.path.join(out, "snapshots")) if f.endswith(".vtm"))
    p = env.run("post", out)
    check(p.returncode == 0, f"post: exit {p.returncode}: {p.stderr[-400:]}")
    check_reproduced(os.path.join(out, "probes"), os.path.join(out, "post", "probes"), [str(s) for s in snapshots], "steered")
    os.rename(os.path.join(out, "steering.log"), os.path.join(out, "steering.off"))
    p = env.run("post", out, "--out", env.path("unsteered"))
    check(p.returncode == 0, f"post without the log: exit {p.returncode}")
    run, plain = probe_rows(os.path.join(out, "probes")), probe_rows(env.path("unsteered", "probes"))
    check(any(plain["wall"][1][s] != run["wall"][1][s] for s in plain["wall"][1]),
          "the gauge reads the same with and without the steered motion: the test cannot tell")
    # A log that names a motion the case does not have is bad input, naming the file.
    with open(os.path.join(out, "steering.log"), "w") as f:
        f.write("20 0.0 motion_amplitude 4 2\n")
    p = env.run("post", out, "--out", env.path("bad"))
    check(p.returncode == 2 and "steering.log" in p.stderr, f"a bad steering.log: exit {p.returncode}: {p.stderr[-300:]}")


@test
def post_reads_run_folders_of_earlier_versions(env):
    """A run folder of spate before 0.1 (raw snapshots without field data, a checkpoint without the
    pressures, no case.yaml): post takes the case from the checkpoint, reads the snapshots as they
    are, and recomputes the checkpoint's pressures with a warning (close to the snapshot's)."""
    old = os.path.join(source_dir(env), "tests", "fixtures", "run_v0_tiny_2d")
    probe = "{name: p, type: pressure, position: [0.01, 0.005]}"
    p = env.run("post", old, "--probe", probe, "--out", env.path("snapshots"))
    check(p.returncode == 0, f"post on snapshots: exit {p.returncode}")
    from_snapshots = probe_rows(env.path("snapshots", "probes"))["p"][1]
    check(sorted(from_snapshots, key=int) == ["0", "3"], f"steps {sorted(from_snapshots)}")
    p = env.run("post", old, "--probe", probe, "--from", "checkpoints", "--out", env.path("checkpoints"))
    check(p.returncode == 0 and "recomputed from the densities" in p.stderr, "no warning about the recomputed pressures")
    from_checkpoint = probe_rows(env.path("checkpoints", "probes"))["p"][1]
    a, b = float(from_snapshots["3"].split(",")[2]), float(from_checkpoint["3"].split(",")[2])
    check(a > 10 and abs(a - b) < 0.05 * a, f"pressure at step 3: {a} Pa from the snapshot, {b} Pa recomputed")
    check(from_snapshots["3"].split(",")[0] == from_checkpoint["3"].split(",")[0], "times differ")


# ---- spate plot ---------------------------------------------------------------------------------

def png_size(path):
    with open(path, "rb") as f:
        head = f.read(24)
    check(head[:8] == b"\x89PNG\r\n\x1a\n", f"{path} is not a PNG")
    return int.from_bytes(head[16:20], "big"), int.from_bytes(head[20:24], "big")


@test
def plot_every_probe(env):
    """spate plot RUN_DIR draws one PNG per probe; spate post --plot plots what post wrote."""
    out = env.path("run")
    p = env.run("run", os.path.join(env.cases, "probes_2d.yaml"), "--out", out, "--until", "0.01", "--quiet")
    check(p.returncode == 0, f"run: exit {p.returncode}")
    p = env.run("plot", out)
    check(p.returncode == 0, f"plot: exit {p.returncode}: {p.stderr}")
    probes = sorted(f[:-4] for f in os.listdir(os.path.join(out, "probes")))
    plots = sorted(f[:-4] for f in os.listdir(os.path.join(out, "plots")))
    check(plots == probes, f"plots {plots} for probes {probes}")
    for name in plots:
        w, h = png_size(os.path.join(out, "plots", name + ".png"))
        check(w >= 800 and h >= 450, f"{name}.png is {w} x {h}")
    p = env.run("post", out, "--plot", "--probe", "{name: deep, type: height, position: [0.02], connected: true}")
    check(p.returncode == 0 and os.listdir(os.path.join(out, "post", "plots")) == ["deep.png"], "post --plot")
    p = env.run("plot", env.path("nowhere"))
    check(p.returncode == 2 and "probes/" in p.stderr, "plot of a folder without probes")


# ---- cmake --install ----------------------------------------------------------------------------

@test
def install_tree(env):
    """cmake --install puts the program, the pipelines, the plot script, the cases and the docs under
    a prefix, and the installed spate finds its data there (not in the source tree)."""
    build = os.path.dirname(os.path.dirname(env.spate))
    prefix = env.path("prefix")
    p = subprocess.run(["cmake", "--install", build, "--prefix", prefix], capture_output=True, text=True)
    check(p.returncode == 0, f"cmake --install: exit {p.returncode}: {p.stderr[-2000:]}")
    for f in ["bin/spate", "share/spate/pipelines/free_surface.py", "share/spate/pipelines/live.py",
              "share/spate/pipelines/spate_steering.xml", "share/spate/scripts/plot_probes.py",
              "share/spate/cases/dam_break_column_3d.yaml", "share/doc/spate/README.md", "share/doc/spate/docs/cli.md"]:
        check(os.path.isfile(os.path.join(prefix, f)), f"{f} not installed")
    spate = os.path.join(prefix, "bin", "spate")
    env_clean = {k: v for k, v in os.environ.items() if k not in ("SPATE_DATA_DIR", "SPATE_PIPELINES_DIR")}
    p = subprocess.run([spate, "--version"], capture_output=True, text=True, env=env_clean)
    check(p.returncode == 0 and p.stdout.startswith("spate "), f"installed spate --version: {p.stdout!r}")
    out = env.path("run")
    p = subprocess.run([spate, "run", os.path.join(prefix, "share/spate/cases/dam_break_2d.yaml"), "--steps", "3", "--out", out,
                        "--quiet"], capture_output=True, text=True, env=env_clean)
    check(p.returncode == 0, f"installed spate run: exit {p.returncode}")
    p = subprocess.run([spate, "plot", out, "--log-level", "debug"], capture_output=True, text=True, env=env_clean)
    check(p.returncode == 0 and os.path.join(prefix, "share/spate/scripts/plot_probes.py") in p.stdout,
          f"the installed spate plot does not use the installed script: {p.stdout}{p.stderr}")


if __name__ == "__main__":
    sys.exit(main(TESTS))
