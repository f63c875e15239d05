#!/usr/bin/env python3
"""Robustness of the real `spate` program against bad input, failing outputs and unusual runs
(issue 14): crafted checkpoints, steering logs and case files, full disks, unusable output folders,
memory too small for the run, zero and tiny intervals, fluid leaving through open sides, signals.
Every crafted file is made by the test itself. Bad input must end with exit 2 and one message that
names the file, the key or dataset and the reason, HDF5's own diagnostics never printed; no run may
crash, hang or end with exit 4.

    robustness_tests.py --spate build/bin/spate --cases tests/cases --shipped cases --work DIR NAME
    robustness_tests.py ... --list          prints the test names (CTest registers one per name)
"""
import json
import os
import re
import resource
import shutil
import signal
import subprocess
import sys
import time

import h5py
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path[:0] = [HERE, os.path.join(HERE, "..", "integration")]
import checkpoint_tools as ck  # noqa: E402
import cli_tests  # noqa: E402  (the integration tests' Env, Failure and check)
from cli_tests import Failure, check  # noqa: E402

TESTS = {}
ERROR_LINE = re.compile(r"^(\d{4}-\d\d-\d\dT[\d:.]+Z )?spate: error: ")


def test(fn):
    TESTS[fn.__name__] = fn
    return fn


class Result:
    def __init__(self, returncode, stdout, stderr, maxrss_kib, seconds):
        self.returncode, self.stdout, self.stderr = returncode, stdout, stderr
        self.maxrss_kib, self.seconds = maxrss_kib, seconds


class Env(cli_tests.Env):
    def __init__(self, args, name):
        super().__init__(args, name)
        self.spill = os.path.join(self.cases, "spill_2d.yaml")
        self.dam_break = os.path.join(self.shipped, "dam_break_2d.yaml")

    def run(self, *argv, timeout=120, limits=None, quiet=False, prefix=()):
        """Runs spate; `limits`: {resource.RLIMIT_*: bytes} for the child. Returns a Result with the
        child's own peak memory (wait4)."""
        env = dict(os.environ, OMP_NUM_THREADS=os.environ.get("OMP_NUM_THREADS", "1"))

        def preexec():
            for res, value in (limits or {}).items():
                resource.setrlimit(res, (value, value))
        cmd = [*prefix, self.spate, *argv]
        begin = time.monotonic()
        p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=self.work, env=env,
                             preexec_fn=preexec if limits else None)
        try:
            out, err = p.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            p.kill()
            p.communicate()
            raise Failure(f"no answer after {timeout} s (a hang): spate {' '.join(argv)}")
        # The child is reaped by communicate(); its rusage is the largest of the children so far,
        # so the peak-memory checks run a fresh child per measurement (maxrss_kib is then its own).
        usage = resource.getrusage(resource.RUSAGE_CHILDREN)
        r = Result(p.returncode, out, err, usage.ru_maxrss, time.monotonic() - begin)
        if not quiet:
            print("$ spate " + " ".join(argv))
            print(f"  exit {r.returncode} in {r.seconds:.1f} s")
            for line in (out + err).strip().splitlines()[:12]:
                print("  | " + line[:300])
        check(r.returncode >= 0, f"spate died of signal {-r.returncode}: spate {' '.join(argv)}")
        check(r.returncode != 4, f"internal error (exit 4): {err.strip()}")
        check("HDF5-DIAG" not in err, "HDF5 printed its own diagnostics")
        return r

    def write(self, name, text):
        return self.write_case(name, text)

    def checkpoint(self, case=None, steps=3, name="source", extra=()):
        """A real checkpoint of `case` (default tiny_2d) after `steps` steps."""
        out = self.path(name)
        r = self.run("run", case or self.tiny, "--steps", str(steps), "--out", out, "--quiet", *extra, quiet=True)
        check(r.returncode == 0, f"making a checkpoint: exit {r.returncode}: {r.stderr}")
        path = os.path.join(out, "checkpoints", f"checkpoint_step_{steps:08d}.h5")
        check(os.path.isfile(path), f"no checkpoint {path}")
        return path


def expect_bad(env, argv, *needles, command="run"):
    """spate COMMAND argv: exit 2, every needle in the one-message stderr; a run leaves only the
    summary.json of the refusal in its output folder."""
    out = env.path("out_must_not_exist")
    full = [command, *argv] + (["--out", out, "--quiet"] if command == "run" else [])
    r = env.run(*full)
    check(r.returncode == 2, f"exit {r.returncode}, expected 2 (bad input): {r.stderr.strip()}")
    message = r.stderr.strip()
    # One line "spate: error: ..." (after a timestamp when stderr is not a terminal, docs/cli.md).
    check(ERROR_LINE.match(message) and len(message.splitlines()) == 1, f"not one clear message: {message}")
    for n in needles:
        if isinstance(n, re.Pattern):
            check(n.search(message), f"message does not match /{n.pattern}/: {message}")
        else:
            check(n in message, f"'{n}' not in the message: {message}")
    if command == "run":
        cli_tests.check_refused(out, message)  # only its summary.json
    return message


def summary(out):
    with open(os.path.join(out, "summary.json")) as f:
        return json.load(f)


# ---- checkpoints --------------------------------------------------------------------------------

def crafted_checkpoints(env, source):
    """(name, edit, needles, restart?) for every class of damage; the edits change one thing."""
    with h5py.File(source, "r") as f:
        n = f["particles/id"].shape[0]
        case_yaml = ck.text_attr(f, "case_yaml")

    def dataset(name, data_fn, **kw):
        def edit(f):
            ck.replace_dataset(f, name, data_fn(f["particles/" + name][...]), **kw)
        return edit

    def attr(name, value):
        def edit(f):
            del f.attrs[name]
            f.attrs[name] = value
        return edit

    def steering(text):
        def edit(f):
            ck.set_text(f, "steering_log", text)
            ck.resign(f)
        return edit

    def values(name, change):
        def edit(f):
            d = f["particles/" + name][...]
            change(d)
            ck.replace_dataset(f, name, d)
        return edit

    def unwritten(f):
        del f["particles/x"]
        f.create_dataset("particles/x", shape=(n,), dtype="f4", chunks=True, fletcher32=True)

    def external_link(f):
        # particles/x in another file, reached through an external link.
        other = os.path.join(os.path.dirname(f.filename), "elsewhere.h5")
        with h5py.File(other, "w") as g:
            g["x"] = f["particles/x"][...]
        del f["particles/x"]
        f["particles/x"] = h5py.ExternalLink(other, "/x")

    def external_storage(f):
        # particles/y's values in a raw file beside it (HDF5 external storage).
        raw = os.path.join(os.path.dirname(f.filename), "raw.bin")
        d = f["particles/y"][...]
        d.tofile(raw)
        del f["particles/y"]
        f.create_dataset("particles/y", shape=d.shape, dtype=d.dtype, external=[(raw, 0, d.nbytes)])

    def case_text(text):
        def edit(f):
            ck.set_text(f, "case_yaml", text)
            ck.resign(f)
        return edit

    def other_geometry(f):
        # Another spacing, the hash left as it was: the header is consistent, the hash is not.
        ck.set_text(f, "case_yaml", case_yaml.replace("dp: 0.005", "dp: 0.004"))
        ck.resign(f)

    return [
        ("longer_dataset", dataset("vx", lambda d: np.concatenate([d, np.zeros(10, "f4")])), ["particles/vx", f"{n + 10} values"]),
        ("rank_2_dataset", dataset("x", lambda d: d.reshape(n, 1)), ["particles/x", "rank 2"]),
        ("shorter_dataset", dataset("density", lambda d: d[:-10]), ["particles/density", f"{n - 10} values"]),
        ("unwritten_dataset", unwritten, ["particles/x", "unwritten"]),
        ("missing_dataset", lambda f: f.__delitem__("particles/material"), ["particles/material", "missing"]),
        ("double_dataset", dataset("y", lambda d: d.astype("f8")), ["particles/y", "32-bit floats"]),
        ("no_checksum", dataset("x", lambda d: d, fletcher32=False), ["particles/x", "Fletcher32"]),
        ("external_link", external_link, ["particles/x", "link to elsewhere"]),
        ("external_storage", external_storage, ["particles/y", "outside the file"]),
        ("dimensions_1000", attr("dimensions", np.int32(1000)), ["attribute 'dimensions'", "1000"]),
        ("dimensions_array", attr("dimensions", np.arange(1000, dtype="i4")), ["attribute 'dimensions'", "single value"]),
        ("dimensions_text", attr("dimensions", "three"), ["attribute 'dimensions'", "integer"]),
        ("time_nan", attr("time", np.float64("nan")), ["attribute 'time'", "finite"]),
        ("step_negative", attr("step", np.int64(-5)), ["attribute 'step'", "-5"]),
        ("step_huge", attr("step", np.int64(10**18)), ["attribute 'step'"]),
        ("dt_zero", attr("dt", np.float64(0)), ["attribute 'dt'", "> 0"]),
        ("removed_negative", attr("removed_particles", np.int64(-3)), ["removed_particles"]),
        ("nan_position", values("x", lambda d: d.__setitem__(5, np.nan)), ["particles/x", "not finite"]),
        ("infinite_velocity", values("vy", lambda d: d.__setitem__(7, np.inf)), ["particles/vy", "not finite"]),
        ("outside_domain", values("y", lambda d: d.__setitem__(5, 50.0)), ["particles/y", "outside the domain"]),
        ("unknown_material", values("material", lambda d: d.__setitem__(0, 77)), ["particles/material", "material 77"]),
        ("duplicate_id", values("id", lambda d: d.__setitem__(1, d[0])), ["particles/id", "appears twice"]),
        ("id_out_of_range", values("id", lambda d: d.__setitem__(0, 10**6)), ["particles/id", "out of range"]),
        ("negative_density", values("density", lambda d: d.__setitem__(3, -1.0)), ["particles/density"]),
        ("steering_malformed", steering("2 0.0001 gravity 1\n"), ["steering_log", "gravity takes 3"]),
        ("steering_too_strong", steering("2 0.0001 gravity 0 -1e30 0\n"), ["steering_log", "exceeds 100"]),
        ("steering_overflow", steering("2 0.0001 viscosity 1e400\n"), ["steering_log", "out of range"]),
        ("steering_garbage", steering("no numbers here\n"), ["steering_log", "not a step number"]),
        ("steering_unknown_fluid", steering("2 0.0001 phase_viscosity 3 0.5\n"), ["steering_log", "no fluid 3"]),
        ("steering_after_step", steering("99 0.1 viscosity 0.002\n"), ["steering_log", "after the checkpoint's step"]),
        ("format", attr("format", np.bytes_(b"something-else")), ["not a spate checkpoint"]),
        ("second_yaml_document", case_text(case_yaml + "\n---\nname: other\n"), ["case_yaml", "second YAML document"]),
        ("case_garbage", case_text("{{{"), ["case_yaml"]),
        ("hash_of_other_geometry", other_geometry, ["geometry_hash"]),
        ("header_edited", lambda f: ck.set_text(f, "case_name", "renamed"), ["header_checksum", "damaged"]),
    ]


def check_crafted(env, subset):
    source = env.checkpoint()
    for name, edit, needles in crafted_checkpoints(env, source):
        if name not in subset:
            continue
        path = ck.mutant(source, env.path(name + ".h5"), edit)
        print(f"-- {name}")
        # Read as compare reads it (no case), and as a restart reads it (against the case).
        expect_bad(env, [path, source], path, *needles, command="compare")
        expect_bad(env, [env.tiny, "--restart", path, "--steps", "1"], path, *needles)


@test
def checkpoint_shapes_and_types(env):
    check_crafted(env, {"longer_dataset", "rank_2_dataset", "shorter_dataset", "unwritten_dataset", "missing_dataset",
                        "double_dataset", "no_checksum", "external_link", "external_storage", "dimensions_1000",
                        "dimensions_array", "dimensions_text", "format"})


@test
def checkpoint_values(env):
    check_crafted(env, {"time_nan", "step_negative", "step_huge", "dt_zero", "removed_negative", "nan_position",
                        "infinite_velocity", "outside_domain", "unknown_material", "duplicate_id", "id_out_of_range",
                        "negative_density"})


@test
def checkpoint_header_and_history(env):
    check_crafted(env, {"steering_malformed", "steering_too_strong", "steering_overflow", "steering_garbage",
                        "steering_unknown_fluid", "steering_after_step", "second_yaml_document", "case_garbage", "hash_of_other_geometry",
                        "header_edited"})


@test
def checkpoint_corruption(env):
    """Flipped bits in the data (Fletcher32) and in the header, a truncated file, a folder."""
    source = env.checkpoint()
    for field in ("x", "density", "id"):
        damaged = env.path(f"flip_{field}.h5")
        shutil.copyfile(source, damaged)
        offset, size = ck.chunk_offset(damaged, field)
        ck.flip_byte(damaged, offset + size // 2)
        expect_bad(env, [damaged, source], damaged, f"particles/{field}", "damaged", command="compare")
    # The bytes of the time attribute's value, wherever HDF5 put them in the header.
    with h5py.File(source, "r") as f:
        t = float(f.attrs["time"])
    raw = open(source, "rb").read()
    at = raw.find(np.float64(t).tobytes())
    check(at > 0, "time attribute not found in the file")
    damaged = env.path("flip_time.h5")
    shutil.copyfile(source, damaged)
    ck.flip_byte(damaged, at + 3, 0x01)
    expect_bad(env, [damaged, source], damaged, command="compare")
    truncated = env.path("truncated.h5")
    with open(truncated, "wb") as f:
        f.write(raw[: len(raw) * 2 // 3])
    expect_bad(env, [truncated, source], truncated, command="compare")
    folder = env.path("folder.h5")
    os.makedirs(folder)
    expect_bad(env, [env.tiny, "--restart", folder], folder, "folder")


@test
def checkpoint_declaring_many_particles(env):
    """2e8 particles declared, nothing stored: refused before anything is allocated."""
    source = env.checkpoint()
    baseline = env.run("compare", source, source)
    check(baseline.returncode == 0, "the source checkpoint must compare equal to itself")

    def declare(f):
        for name in list(f["particles"].keys()):
            dtype = f["particles/" + name].dtype
            del f["particles/" + name]
            f.create_dataset("particles/" + name, shape=(200_000_000,), dtype=dtype, chunks=(65536,), fletcher32=True)
    big = ck.mutant(source, env.path("big.h5"), declare)
    check(os.path.getsize(big) < 10_000_000, "the crafted file itself must be small")
    # A fresh measurement: RUSAGE_CHILDREN is the largest child so far, and the baseline ran first.
    r = expect_bad(env, [big, source], big, "200000000", command="compare")
    peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    check(peak < 1_000_000, f"peak memory {peak} KiB: the particles were allocated")
    print(f"  refused with a peak of {peak / 1024:.0f} MiB for all runs so far ({r[:80]}...)")


@test
def checkpoint_of_another_case(env):
    """The same particle count, another geometry (the fluid block on the other side): refused."""
    mirrored = env.write("mirrored.yaml", env.tiny_text().replace("  - min: [0, 0]\n    max: [0.05, 0.03]",
                                                                  "  - min: [0.05, 0]\n    max: [0.1, 0.03]"))
    a = json.loads(env.run("info", env.tiny, "--json", quiet=True).stdout)["particles"]
    b = json.loads(env.run("info", mirrored, "--json", quiet=True).stdout)["particles"]
    check(a == b, f"test bug: the mirrored case must have the same counts ({a} vs {b})")
    other = env.checkpoint(mirrored, name="mirrored_run")
    expect_bad(env, [env.tiny, "--restart", other, "--steps", "1"], other, "another particle set", "fluid_blocks[0]")
    # Its own case takes it back.
    r = env.run("run", mirrored, "--restart", other, "--steps", "2", "--out", env.path("continued"), "--quiet")
    check(r.returncode == 0, f"restart with its own case: exit {r.returncode}")


@test
def checkpoint_formats_accepted(env):
    """What must still be read: strings stored as HDF5 variable-length strings (h5py's default),
    and the format 2 of earlier spate versions (no checksums; format 1, before the field
    registry, is Restart.ReadsFormatVersionOneBitIdentically's); both continue bit-identically."""
    straight = env.checkpoint(steps=6, name="straight")
    source = env.checkpoint(steps=3)
    def vlen(f):
        for name in ("case_yaml", "case_name", "steering_log", "geometry_hash"):
            ck.set_text(f, name, ck.text_attr(f, name), variable_length=True)
    for label, edit in (("vlen", vlen), ("legacy", ck.to_legacy_format)):
        path = ck.mutant(source, env.path(label + ".h5"), edit)
        r = env.run("compare", path, source)
        check(r.returncode == 0 and "MATCH" in r.stdout, f"{label}: compare exit {r.returncode}")
        out = env.path("from_" + label)
        r = env.run("run", env.tiny, "--restart", path, "--steps", "3", "--out", out, "--quiet")
        check(r.returncode == 0, f"{label}: restart exit {r.returncode}")
        r = env.run("compare", straight, os.path.join(out, "checkpoints", "checkpoint_step_00000006.h5"))
        check(r.returncode == 0, f"{label}: the restart is not bit-identical")


# ---- steering logs and case files ---------------------------------------------------------------

@test
def steering_logs(env):
    def log(name, text, mode="w"):
        path = env.path(name)
        with open(path, mode) as f:
            f.write(text)
        return path
    folder = env.path("log_folder")
    os.makedirs(folder)
    expect_bad(env, [env.tiny, "--steering-log", folder], folder, "folder")
    # Not files at all: a device that never ends, a FIFO nobody writes to (reads that never end).
    fifo = env.path("log_fifo")
    os.mkfifo(fifo)
    for path in ("/dev/zero", fifo):
        expect_bad(env, [env.tiny, "--steering-log", path], path, "not a regular file")
    big = env.path("big.log")
    with open(big, "w") as f:
        f.truncate(17 << 20)
    expect_bad(env, [env.tiny, "--steering-log", big], big, "too large")
    expect_bad(env, [env.tiny, "--steering-log", env.path("missing.log")], "missing.log", "cannot read")
    path = log("garbage.log", "# a comment\n3 0.001 viscosity 0.002\nthis is not a change\n")
    expect_bad(env, [env.tiny, "--steering-log", path], f"{path}:3", "not a step number")
    path = log("overflow.log", "1 0.0002 gravity 0 1e400 0\n")
    expect_bad(env, [env.tiny, "--steering-log", path], f"{path}:1", "1e400", "out of range")
    path = log("strong.log", "1 0.0002 gravity 0 -1e30 0\n")
    expect_bad(env, [env.tiny, "--steering-log", path], f"{path}:1", "exceeds 100")
    path = log("nan.log", "1 0.0002 viscosity nan\n")
    expect_bad(env, [env.tiny, "--steering-log", path], f"{path}:1", "not finite")
    path = log("unknown.log", "1 0.0002 warp_speed 9\n")
    expect_bad(env, [env.tiny, "--steering-log", path], f"{path}:1", "unknown parameter")
    path = log("backwards.log", "5 0.001 viscosity 0.002\n2 0.0004 viscosity 0.003\n")
    expect_bad(env, [env.tiny, "--steering-log", path], f"{path}:2", "decrease")
    path = log("binary.log", "1 0.0002 viscosity \0\0\x01\n")
    expect_bad(env, [env.tiny, "--steering-log", path], path, "binary")
    # A good log replays.
    path = log("good.log", "# spate steering log\n2 0.0004 viscosity 0.002\n4 0.0008 gravity 0 -5 0\n")
    out = env.path("replayed")
    r = env.run("run", env.tiny, "--steering-log", path, "--steps", "6", "--out", out, "--quiet")
    check(r.returncode == 0, f"a valid log: exit {r.returncode}")
    check(summary(out)["steering"]["accepted"] == 2, "both changes applied")


@test
def case_files(env):
    two = env.write("two_documents.yaml", env.tiny_text() + "---\nname: second\n")
    expect_bad(env, [two], two, "second YAML document")
    expect_bad(env, [two], two, "second YAML document", command="info")
    # Case "files" that are not files: no read that never ends, no memory filled.
    fifo = env.path("case_fifo.yaml")
    os.mkfifo(fifo)
    for path in ("/dev/zero", "/dev/urandom", fifo):
        expect_bad(env, [path], path, "not a regular file", command="info")
        expect_bad(env, [path], path, "not a regular file")
    big = env.write("big.yaml", env.tiny_text() + "#" * (17 << 20) + "\n")
    expect_bad(env, [big], big, "too large")
    for name in ["../escape", "/abs/path", "a/b", "..", ".hidden"]:
        expect_bad(env, [env.tiny, "--set", f"name={name}"], "'name'", name)
        expect_bad(env, [env.tiny, "--set", f"probes=[{{name: '{name}', type: front}}]"], "'probes[0].name'", name)
    check(not os.path.exists(os.path.join(os.path.dirname(env.work), "escape")), "a name escaped the output folder")
    expect_bad(env, [env.tiny, "--set", "dp=1e-12"], "'dp'", "too fine")
    expect_bad(env, [env.tiny, "--set", "tank.origin=[1e300, 0]"], "'tank.origin'", "1e+300")
    expect_bad(env, [env.tiny, "--set", "tank.max_removed_fraction=2"], "'tank.max_removed_fraction'")


# ---- outputs ------------------------------------------------------------------------------------

@test
def bad_output_folder(env):
    a_file = env.write("a_file", "x")
    for out in [a_file, os.path.join(a_file, "below"), "/proc/spate_cannot_write_here"]:
        r = env.run("run", env.tiny, "--steps", "1", "--out", out, "--quiet")
        check(r.returncode == 2, f"--out {out}: exit {r.returncode}, expected 2")
        check("--out" in r.stderr and out in r.stderr, f"the message names the option and folder: {r.stderr}")
    check(open(a_file).read() == "x", "the file in the way was touched")


def full_disk_prefix(env, folder, size):
    """A command prefix that runs spate with `folder` on a tmpfs of `size` (a private mount
    namespace), or None where mounting is not allowed."""
    os.makedirs(folder, exist_ok=True)
    for unshare in (["unshare", "-m"], ["unshare", "-rm"]):
        script = f'mount -t tmpfs -o size={size} tmpfs "$0" && exec "$@"'
        try:
            p = subprocess.run([*unshare, "sh", "-c", script, folder, "true"], capture_output=True, timeout=30)
        except (OSError, subprocess.TimeoutExpired):
            continue
        if p.returncode == 0:
            return [*unshare, "sh", "-c", script, folder]
    return None


@test
def full_disk(env):
    """Outputs that do not fit: exit 5 with the file named, never a crash or exit 0; no output is
    left half written; summary.json says what happened whenever it fits."""
    # 1. A file-size limit (ulimit -f): checkpoints and snapshots do not fit, the summary does.
    out = env.path("fsize")
    r = env.run("run", env.dam_break, "--steps", "5", "--checkpoint-every", "1", "--out", out, "--quiet",
                limits={resource.RLIMIT_FSIZE: 60_000})
    check(r.returncode == 5, f"exit {r.returncode}, expected 5 (an output could not be written)")
    check("File too large" in r.stderr and out in r.stderr, f"the message names the file and the reason: {r.stderr}")
    s = summary(out)
    check(s["exit_status"] == "output_failed" and s["exit_code"] == 5, f"summary: {s['exit_status']}")
    check(s["exit_code"] == r.returncode, "summary and exit code agree")
    for root, _, files in os.walk(out):
        for name in files:
            check(".tmp" not in name, f"a temporary file was left behind: {os.path.join(root, name)}")
    # 2. A really full disk (a small tmpfs), where mounting one is allowed: at every size the run
    # ends with 0 or 5, never a crash; the checkpoints it kept are readable.
    folder = env.path("tmpfs")
    ran = 0
    for size in ("64k", "160k", "400k", "1200k"):
        prefix = full_disk_prefix(env, folder, size)
        if prefix is None:
            print("  (no tmpfs: mounting is not allowed here; the file-size limit above stands in)")
            break
        ran += 1
        out = os.path.join(folder, "out")
        r = env.run("run", env.dam_break, "--steps", "4", "--checkpoint-every", "1", "--out", out, "--quiet", prefix=prefix)
        check(r.returncode in (0, 5), f"tmpfs {size}: exit {r.returncode}, expected 0 or 5")
        if r.returncode == 5:
            check("No space left on device" in r.stderr, f"tmpfs {size}: the reason is named: {r.stderr}")
    print(f"  {ran} tmpfs sizes tried")


@test
def atomic_outputs(env):
    """Probe CSVs hold whole rows, and a restart drops the rows a killed run wrote after its last
    checkpoint; summary.json, snapshots and the index are renamed into place (no .tmp left)."""
    out = env.path("first")
    r = env.run("run", env.dam_break, "--steps", "30", "--checkpoint-every", "10", "--set", "output.probe_interval=0",
                "--out", out, "--quiet")
    check(r.returncode == 0, f"exit {r.returncode}")
    front = os.path.join(out, "probes", "front.csv")
    rows = open(front).read().splitlines()
    check(len(rows) == 32 and rows[0].startswith("time[s],step,front"), f"{len(rows)} lines in front.csv, expected header + 31")
    # As if killed after step 30 with its last periodic checkpoint at 20: a torn line at the end.
    with open(front, "a") as f:
        f.write("0.0123,31,0.05")
    r = env.run("run", env.dam_break, "--restart", os.path.join(out, "checkpoints", "checkpoint_step_00000020.h5"),
                "--steps", "10", "--set", "output.probe_interval=0", "--out", out, "--quiet")
    check(r.returncode == 0, f"restart: exit {r.returncode}")
    again = open(front).read().splitlines()
    steps = [int(line.split(",")[1]) for line in again[1:]]
    check(steps == list(range(0, 31)), f"after the restart the rows are steps 0..30 once each, got {steps[:3]}...{steps[-3:]}")
    check(again[:22] == rows[:22], "the rows up to the checkpoint are kept as they were")
    for root, _, files in os.walk(out):
        for name in files:
            check(".tmp" not in name, f"a temporary file was left: {name}")


@test
def summary_after_every_run(env):
    """summary.json with the exit status after a stop by SIGTERM (exit 143, final checkpoint that a
    restart continues from) and after kill -9 during checkpoints (no summary, but the newest
    checkpoint is readable)."""
    out = env.path("terminated")
    env_vars = dict(os.environ, OMP_NUM_THREADS="1")
    p = subprocess.Popen([env.spate, "run", env.dam_break, "--steps", "100000", "--out", out, "--quiet"],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env_vars)
    deadline = time.monotonic() + 60
    while not os.path.exists(os.path.join(out, "particles.pvd")) and time.monotonic() < deadline:
        time.sleep(0.1)
    time.sleep(0.5)
    p.send_signal(signal.SIGTERM)
    try:
        _, err = p.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        p.kill()
        raise Failure("no stop within 60 s of SIGTERM")
    check(p.returncode == 143, f"exit {p.returncode} after SIGTERM, expected 143")
    s = summary(out)
    check(s["exit_status"] == "interrupted" and s["exit_code"] == 143, f"summary: {s['exit_status']} {s['exit_code']}")
    check(0 < s["steps"] < 100000 and os.path.isfile(s["last_checkpoint"]), f"final checkpoint {s['last_checkpoint']}")
    check("SIGTERM" in err, f"stderr names the signal: {err}")
    r = env.run("run", env.dam_break, "--restart", s["last_checkpoint"], "--steps", "2", "--out", env.path("resumed"), "--quiet")
    check(r.returncode == 0, f"restart from the interrupted run: exit {r.returncode}")

    # kill -9 at random moments of a run that writes a checkpoint every step.
    for k in range(4):
        out = env.path(f"killed_{k}")
        p = subprocess.Popen([env.spate, "run", env.dam_break, "--steps", "100000", "--checkpoint-every", "1", "--out", out,
                              "--quiet"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env_vars)
        folder = os.path.join(out, "checkpoints")
        deadline = time.monotonic() + 60
        while (not os.path.isdir(folder) or not any(f.endswith(".h5") for f in os.listdir(folder))) and time.monotonic() < deadline:
            time.sleep(0.05)
        time.sleep(0.2 + 0.37 * k)
        p.kill()
        p.wait()
        kept = sorted(f for f in os.listdir(folder) if f.endswith(".h5"))
        check(kept, "no checkpoint survived kill -9")
        newest = os.path.join(folder, kept[-1])
        r = env.run("compare", newest, newest, quiet=True)
        check(r.returncode == 0, f"kill -9 #{k}: the newest checkpoint {kept[-1]} is not readable: {r.stderr}")
    print("  4 of 4 kill -9 runs left a readable newest checkpoint")


# ---- memory ---------------------------------------------------------------------------------------

@test
def memory_estimate(env):
    """spate info counts in closed form at any dp; a run that would not fit is refused (exit 2) with
    the estimate and the finest dp that fits, and that dp then runs within the same limit."""
    column = os.path.join(env.shipped, "dam_break_column_3d.yaml")
    r = env.run("info", column, "--set", "dp=0.0002", "--json", timeout=60)
    j = json.loads(r.stdout)
    check(r.returncode == 0 and j["particles"]["total"] > 10_000_000_000, f"{j['particles']}")
    check(j["run_memory_bytes"] > j["particles"]["total"] * 100, "the run estimate covers the particles")
    check(r.seconds < 30, f"spate info took {r.seconds:.1f} s at dp = 0.0002")
    r = env.run("run", column, "--set", "dp=0.0002", "--out", env.path("huge"), "--quiet", timeout=60)
    check(r.returncode == 2 and "memory" in r.stderr and "dp >=" in r.stderr, f"exit {r.returncode}: {r.stderr}")
    cli_tests.check_refused(env.path("huge"), r.stderr)
    # An address-space limit that leaves about 160 MB (info --json reports what is left).
    limit = 6 << 30
    free = json.loads(env.run("info", env.tiny, "--json", limits={resource.RLIMIT_AS: limit}).stdout)["memory_available_bytes"]
    limit = limit - free + (160 << 20)
    r = env.run("run", env.tiny, "--set", "dp=0.00003", "--out", env.path("refused"), "--quiet", limits={resource.RLIMIT_AS: limit})
    check(r.returncode == 2, f"dp = 0.00003 (1.7 million particles) in ~160 MB: exit {r.returncode}, expected 2")
    m = re.search(r"dp >= ([0-9.e-]+) fits", r.stderr)
    check(m and "ulimit -v" in r.stderr, f"message: {r.stderr}")
    dp = m.group(1)
    out = env.path("fits")
    r = env.run("run", env.tiny, "--set", f"dp={dp}", "--steps", "0", "--out", out, "--quiet", limits={resource.RLIMIT_AS: limit},
                timeout=300)
    check(r.returncode == 0, f"dp = {dp} (said to fit): exit {r.returncode}")
    print(f"  dp = {dp}: {summary(out)['particles']['total']} particles ran within the limit")


# ---- intervals ------------------------------------------------------------------------------------

@test
def zero_and_tiny_intervals(env):
    """probe_interval 0 (the default) means every step, a 1e-300 s interval too; no loop spins."""
    probe = "probes=[{name: front, type: front}]"
    out = env.path("every_step")
    r = env.run("run", env.tiny, "--set", probe, "--set", "output.probe_interval=0", "--steps", "8", "--out", out, "--quiet",
                timeout=60)
    check(r.returncode == 0, f"exit {r.returncode}")
    rows = open(os.path.join(out, "probes", "front.csv")).read().splitlines()
    check(len(rows) == 1 + 9, f"{len(rows) - 1} probe rows for steps 0..8")
    out = env.path("tiny")
    r = env.run("run", env.tiny, "--set", probe, "--set", "output.probe_interval=1e-300", "--set", "output.interval=1e-300",
                "--steps", "3", "--out", out, "--quiet", timeout=60)
    check(r.returncode == 0, f"exit {r.returncode}")
    check(len(open(os.path.join(out, "probes", "front.csv")).read().splitlines()) == 1 + 4, "one probe row per step")
    snaps = sorted(f for f in os.listdir(os.path.join(out, "snapshots")) if f.endswith(".vtm"))
    check(len(snaps) == 4, f"one snapshot per step: {snaps}")
    # A fixed step below the resolution of the simulated time: stops, does not spin.
    r = env.run("run", env.tiny, "--set", "time.dt=1e-300", "--set", "time.end=1", "--out", env.path("stuck"), "--quiet",
                timeout=60)
    check(r.returncode in (2, 3), f"a time step that cannot advance t: exit {r.returncode}")
    # The step-count intervals at 0 mean what docs/cases.md says: no snapshots (output.interval),
    # only the final checkpoint (checkpoint_every), no balancing pass (balance_every).
    out = env.path("zeros")
    r = env.run("run", env.tiny, "--set", "output.interval=0", "--set", "output.checkpoint_every=0",
                "--set", "decomposition.balance_every=0", "--devices", "2", "--steps", "5", "--out", out, "--quiet", timeout=60)
    check(r.returncode == 0, f"zero intervals: exit {r.returncode}")
    snapshots = os.path.join(out, "snapshots")
    check(not os.path.isdir(snapshots) or not any(f.endswith(".vtm") for f in os.listdir(snapshots)), "output.interval 0 wrote snapshots")
    kept = sorted(os.listdir(os.path.join(out, "checkpoints")))
    check([k for k in kept if k.endswith(".h5")] == ["checkpoint_step_00000005.h5"], f"checkpoint_every 0: {kept}")
    check(summary(out)["imbalance_history"] == [], "balance_every 0 balanced")
    # Intervals that cannot mean anything are bad input, never a loop: in-situ every 0 steps, a
    # negative time interval, a steering change to a fractional in-situ interval.
    expect_bad(env, [env.tiny, "--set", "output.interval=-1"], "'output.interval'", ">= 0")
    expect_bad(env, [env.tiny, "--set", "output.probe_interval=-1e-300"], "'output.probe_interval'")
    expect_bad(env, [env.tiny, "--set", "output.checkpoint_every=-1"], "'output.checkpoint_every'")
    expect_bad(env, [env.tiny, "--set", "insitu.every=0"], "'insitu.every'", ">= 1")
    expect_bad(env, [env.tiny, "--checkpoint-every", "-1"], "--checkpoint-every")
    log = env.write("fraction.log", "1 0.0002 insitu_every 0.5\n")
    expect_bad(env, [env.tiny, "--steering-log", log], "insitu_every")


# ---- open sides -----------------------------------------------------------------------------------

@test
def open_sides(env):
    """Fluid that splashes over the walls of an open tank is removed and counted; the run goes on,
    and a restart after removals continues bit-identically on another split with the count carried
    on (splits: decomposition.removal.*); beyond tank.max_removed_fraction the run stops (exit 3)."""
    out = env.path("straight")
    r = env.run("run", env.spill, "--checkpoint-every", "650", "--out", out)
    check(r.returncode == 0, f"exit {r.returncode}")
    s = summary(out)
    removed = s["removed_particles"]
    check(removed > 0 and len(s["removed_first_ids"]) == min(10, removed), f"nothing removed: {removed}")
    check(abs(s["removed_fraction"] - removed / s["particles"]["fluid"]) < 1e-12, "removed_fraction")
    check(sum(s["device_particles"]) == s["particles"]["total"] - removed, "device_particles count the rest")
    check(re.search(r"warning: step \d+, t = \S+ s: \d+ fluid particles? left the domain .* removed \(ids? \d+", r.stderr),
          f"no warning naming the ids: {r.stderr}")
    check(f"{removed} fluid particle" in r.stdout, f"the final line counts the removed fluid: {r.stdout}")
    # Restart from a checkpoint after the first removals, on two devices: the same end.
    middle = os.path.join(out, "checkpoints", "checkpoint_step_00000650.h5")
    with h5py.File(middle, "r") as f:
        carried = int(f.attrs["removed_particles"])
    check(0 < carried <= removed, f"the checkpoint records the particles removed before it ({carried})")
    resumed = env.path("resumed")
    r = env.run("run", env.spill, "--restart", middle, "--devices", "2", "--out", resumed, "--quiet")
    check(r.returncode == 0, f"restart: exit {r.returncode}")
    check(summary(resumed)["removed_particles"] == removed, "the restart counts the same removals")
    check(env.run("compare", s["last_checkpoint"], summary(resumed)["last_checkpoint"]).returncode == 0,
          "a restart after removals is not bit-identical")
    # The limit.
    out = env.path("limited")
    r = env.run("run", env.spill, "--set", "tank.max_removed_fraction=0.01", "--out", out, "--quiet")
    check(r.returncode == 3 and "tank.max_removed_fraction" in r.stderr, f"exit {r.returncode}: {r.stderr}")
    check(summary(out)["exit_status"] == "unstable", "the summary says unstable")


if __name__ == "__main__":
    sys.exit(cli_tests.main(TESTS, Env))
