#!/usr/bin/env python3
"""Integration tests of the real `spate` program: bad input (exit 2, a message naming the file, key
and reason, nothing written), `info --json`, `compare`, and an unstable run (exit 3).

    cli_tests.py --spate build/bin/spate --cases tests/cases --shipped cases --work DIR NAME
    cli_tests.py ... --list          prints the test names (CTest registers one test per name)

Each test gets an empty folder DIR/NAME; the output folder of a bad run is a path inside it that
must still not exist afterwards.
"""
import argparse
import json
import math
import os
import platform
import re
import shutil
import subprocess
import sys
import tempfile
import time

TESTS = {}


def test(fn):
    TESTS[fn.__name__] = fn
    return fn


class Failure(Exception):
    pass


def check(cond, what):
    if not cond:
        raise Failure(what)


class Env:
    def __init__(self, args, name):
        self.spate = os.path.abspath(args.spate)
        self.cases = os.path.abspath(args.cases)
        self.shipped = os.path.abspath(args.shipped)
        self.work = os.path.join(os.path.abspath(args.work), name)
        shutil.rmtree(self.work, ignore_errors=True)
        os.makedirs(self.work)
        self.tiny = os.path.join(self.cases, "tiny_2d.yaml")

    def run(self, *argv, timeout=120):
        env = dict(os.environ, OMP_NUM_THREADS=os.environ.get("OMP_NUM_THREADS", "1"))
        p = subprocess.run([self.spate, *argv], capture_output=True, text=True, timeout=timeout,
                           cwd=self.work, env=env)
        print("$ spate " + " ".join(argv))
        print(f"  exit {p.returncode}")
        for line in (p.stdout + p.stderr).strip().splitlines()[:30]:
            print("  | " + line)
        return p

    def path(self, *parts):
        return os.path.join(self.work, *parts)

    def write_case(self, name, text):
        path = self.path(name)
        with open(path, "w") as f:
            f.write(text)
        return path

    def tiny_text(self):
        with open(self.tiny) as f:
            return f.read()

    def variant(self, name, old, new):
        """The tiny case with one piece of text replaced (checked to be there)."""
        text = self.tiny_text()
        check(old in text, f"test bug: '{old}' not in tiny_2d.yaml")
        return self.write_case(name, text.replace(old, new, 1))


def check_refused(out, stderr):
    """A run refused as bad input (exit 2) leaves its output folder holding only a summary.json that
    says so, with the message it printed (docs/cli.md); nothing else is written."""
    check(os.path.isdir(out) and sorted(os.listdir(out)) == ["summary.json"],
          f"{out}: a refused run must leave only summary.json, found {sorted(os.listdir(out)) if os.path.isdir(out) else 'nothing'}")
    with open(os.path.join(out, "summary.json")) as f:
        s = json.load(f)
    check(s["exit_status"] == "bad_input" and s["exit_code"] == 2, f"summary.json: {s['exit_status']} {s['exit_code']}")
    check(s["message"] and s["message"] in stderr, f"summary.json's message is not the one printed: {s['message']}")
    shutil.rmtree(out)


def expect_bad_input(env, argv, *needles, command="run", parsed=True):
    """Runs `spate COMMAND argv --out OUT`: exit 2, every needle in stderr; OUT holds only the
    summary.json of the refusal (check_refused), or, for a command line that does not parse
    (`parsed=False`), does not exist."""
    out = env.path("out_must_not_exist")
    full = [command, *argv] + (["--out", out, "--quiet"] if command == "run" else [])
    p = env.run(*full)
    check(p.returncode == 2, f"exit code {p.returncode}, expected 2 (bad input)")
    message = p.stderr
    check(message.strip() != "", "no message on stderr")
    for needle in needles:
        if isinstance(needle, re.Pattern):
            check(needle.search(message), f"message does not match /{needle.pattern}/: {message.strip()}")
        else:
            check(needle in message, f"'{needle}' not in the message: {message.strip()}")
    if command == "run" and parsed:
        check_refused(out, message)
    check(not os.path.exists(out), f"{out} was created by a {command} with bad input")
    check(sorted(os.listdir(env.work)) == sorted(f for f in os.listdir(env.work) if f.endswith(".yaml")),
          f"files written into the working folder: {os.listdir(env.work)}")
    return message


# ---- bad input: the case file -------------------------------------------------------------------

@test
def bad_unreadable_file(env):
    missing = env.path("no_such_case.yaml")
    expect_bad_input(env, [missing], missing, "cannot read")
    expect_bad_input(env, [missing], missing, "cannot read", command="info")


@test
def bad_case_is_a_folder(env):
    folder = env.path("folder.yaml")
    os.makedirs(folder)
    p = env.run("run", folder, "--out", env.path("out_must_not_exist"))
    check(p.returncode == 2, f"exit {p.returncode}")
    check(folder in p.stderr and "cannot read" in p.stderr, "the message does not name the path and the reason")
    check_refused(env.path("out_must_not_exist"), p.stderr)


@test
def bad_yaml_syntax(env):
    # An unclosed flow list breaks the document; the parser reports where it noticed.
    path = env.variant("syntax.yaml", "  size: [0.1, 0.05]", "  size: [0.1, 0.05")
    msg = expect_bad_input(env, [path], "YAML syntax error")
    check(re.search(re.escape(path) + r":\d+:\d+: ", msg), f"no file:line:column in: {msg}")
    expect_bad_input(env, [path], re.compile(re.escape(path) + r":\d+:\d+: "), command="info")


@test
def bad_meshes(env):
    # A solid from a mesh that is missing, empty, open, inside out, inconsistently oriented, with a
    # degenerate triangle, or in millimetres: exit 2, the file, the key and the reason, nothing written.
    # (Skipped where spate was built without VTK: the case is then refused for that reason.)
    meshes = os.path.join(env.shipped, "..", "tests", "data", "meshes")
    probe = env.run("info", env.tiny, "--set", "solids=[{name: s, mesh: " + os.path.join(meshes, "empty.stl") + "}]")
    if "reads no meshes" in probe.stderr:
        print("  (built without mesh support: skipped)")
        return
    for name, reason in [("missing.stl", "no such mesh file"), ("empty.stl", "has no triangles"), ("open.stl", "is not closed"),
                         ("inverted.stl", "inside out"), ("inconsistent.stl", "inconsistent normals"),
                         ("degenerate.stl", "degenerate triangles"), ("cube_mm.stl", "in millimetres")]:
        path = os.path.normpath(os.path.join(meshes, name))
        setting = "solids=[{name: s, mesh: " + path + "}]"
        for command in ("run", "info"):
            expect_bad_input(env, [env.tiny, "--set", setting], path, "'solids[0].mesh'", reason, command=command)


@test
def bad_tank_meshes(env):
    # A tank from a mesh (issue 31) is checked as a solid's: exit 2 naming 'tank.mesh' and the reason.
    meshes = os.path.join(env.shipped, "..", "tests", "data", "meshes")
    probe = env.run("info", env.tiny, "--set", "tank={mesh: " + os.path.join(meshes, "empty.stl") + "}")
    if "reads no meshes" in probe.stderr:
        print("  (built without mesh support: skipped)")
        return
    for name, reason in [("open.stl", "is not closed"), ("inverted.stl", "inside out"), ("empty.stl", "has no triangles")]:
        path = os.path.normpath(os.path.join(meshes, name))
        for command in ("run", "info"):
            expect_bad_input(env, [env.tiny, "--set", "tank={mesh: " + path + "}"], path, "'tank.mesh'", reason, command=command)
    expect_bad_input(env, [env.tiny, "--set", "tank={disc: {centre: [0.05, 0.05], radius: 0.05}, size: [1, 1]}"], "'tank.size'",
                     "shaped tank")


@test
def run_writes_the_shaped_tank(env):
    """A shaped tank's surface, geometry/tank.vtp, and, as it moves, its particles' start positions
    (tank_start.vtp), which the in-situ pipeline places the vessel by; spate info names the shape."""
    case = os.path.join(env.shipped, "sloshing_circular_2d.yaml")
    p = env.run("run", case, "--set", "output.interval=0", "--steps", "1", "--out", "tank", "--quiet")
    check(p.returncode == 0, f"exit {p.returncode}: {p.stderr}")
    check(sorted(os.listdir(env.path("tank", "geometry"))) == ["tank.vtp", "tank_start.vtp"],
          f"geometry: {sorted(os.listdir(env.path('tank', 'geometry')))}")
    p = env.run("info", case)
    check(re.search(r"shape +tank: disc of radius 0.2 m", p.stdout), f"no tank shape in spate info: {p.stdout}")


@test
def info_reports_meshes(env):
    p = env.run("info", os.path.join(env.shipped, "dam_break_wedge_2d.yaml"), "--json")
    if p.returncode == 2 and "reads no meshes" in p.stderr:
        print("  (built without mesh support: skipped)")
        return
    check(p.returncode == 0, f"exit {p.returncode}")
    shapes = json.loads(p.stdout)["shapes"]
    check(len(shapes) == 1 and shapes[0]["owner"] == "solids[0] 'ramp'" and shapes[0]["triangles"] == 12,
          f"shapes: {shapes}")
    check(abs(shapes[0]["bounds_max"][0] - 1.3) < 1e-6 and abs(shapes[0]["perimeter"] - (0.6 + 0.1 ** 0.5)) < 1e-6,
          f"bounds or perimeter: {shapes[0]}")
    p = env.run("info", os.path.join(env.shipped, "dam_break_wedge_2d.yaml"))
    check(re.search(r"shape +solids\[0\] 'ramp': mesh '.*wedge.stl': 12 triangles", p.stdout), "no shape line in spate info")


@test
def run_writes_solid_geometry(env):
    """geometry/solid_<material>.vtp for every shaped solid and moving box; the start positions and
    ids of a moving solid's particles in solid_<material>_start.vtp (what the in-situ pipeline fits
    the body's pose to)."""
    solids = ("solids=[{name: breakwater, mesh: meshes/breakwater.stl},"
              " {name: pile, cylinder: {centre: [1.25, 0.305, 0.25], radius: 0.04, length: 0.5, axis: z},"
              "  motion: {period: 0.12, rotation: 20, axis: [0, 1, 0], centre: [1.25, 0.305, 0]}},"
              " {name: crate, min: [0.5, 0.1, 0], max: [0.6, 0.2, 0.1], motion: {period: 1, translation: [0.01, 0, 0]}}]")
    p = env.run("run", os.path.join(env.shipped, "dam_break_breakwater_3d.yaml"), "--set", solids, "--set", "dp=0.04",
                "--set", "probes=[]", "--set", "output.interval=0", "--steps", "1", "--out", "run", "--quiet")
    if p.returncode == 2 and "reads no meshes" in p.stderr:
        print("  (built without mesh support: skipped)")
        return
    check(p.returncode == 0, f"exit {p.returncode}")
    geometry = env.path("run", "geometry")
    # Materials: water 0, tank 1, breakwater 2, pile 3, crate 4.
    check(sorted(os.listdir(geometry)) == ["solid_2.vtp", "solid_3.vtp", "solid_3_start.vtp", "solid_4.vtp", "solid_4_start.vtp"],
          f"geometry: {sorted(os.listdir(geometry))}")
    with open(os.path.join(geometry, "solid_4.vtp")) as f:
        check('NumberOfPoints="8" NumberOfPolys="6"' in f.read(), "the crate's box surface")
    with open(os.path.join(geometry, "solid_3_start.vtp")) as f:
        text = f.read()
    n = int(re.search(r'NumberOfPoints="(\d+)"', text).group(1))
    ids = [int(v) for v in re.search(r'Name="id" format="ascii">\n(.*?)</DataArray>', text, re.S).group(1).split()]
    points = re.search(r'NumberOfComponents="3" format="ascii">\n(.*?)</DataArray>', text, re.S).group(1).split()
    xyz = [tuple(float(v) for v in points[k:k + 3]) for k in range(0, len(points), 3)]
    check(n > 20 and len(ids) == n == len(xyz) and len(set(ids)) == n, f"{n} points, {len(ids)} ids")
    # The pile's particles at the start: inside its cylinder (a lattice site under its surface).
    worst = max(((x - 1.25) ** 2 + (y - 0.305) ** 2) ** 0.5 for x, y, z in xyz)
    check(worst <= 0.04 + 1e-6 and min(z for _, _, z in xyz) >= 0, f"a start position outside the pile: {worst}")


@test
def bad_yaml_not_a_map(env):
    path = env.write_case("list.yaml", "- 1\n- 2\n")
    expect_bad_input(env, [path], path, "map")


@test
def bad_unknown_key(env):
    # A misspelt key in the right section, and a key in the wrong section.
    path = env.variant("typo.yaml", "  viscosity: 0.001", "  viscocity: 0.001")
    expect_bad_input(env, [path], f"{path}:", "'fluid.viscocity'", "unknown key", "did you mean 'fluid.viscosity'")
    path = env.variant("misplaced.yaml", "dp: 0.005", "dp: 0.005\nviscocity: 0.001")
    expect_bad_input(env, [path], f"{path}:", "'viscocity'", "unknown key", "did you mean 'fluid.viscosity'")
    # The same through --set: the message quotes the option.
    expect_bad_input(env, [env.tiny, "--set", "time.edn=1"], "'time.edn'", "--set time.edn=1", "did you mean 'time.end'")


@test
def bad_duplicate_key(env):
    # YAML parsers keep one of two equal keys silently; spate refuses the case.
    path = env.variant("dup.yaml", "dp: 0.005", "dp: 0.005\ndp: 0.01")
    expect_bad_input(env, [path], re.compile(re.escape(path) + r":\d+:1: key 'dp'"), "given twice")


@test
def bad_wrong_type(env):
    path = env.variant("type.yaml", "dp: 0.005", "dp: fine")
    expect_bad_input(env, [path], re.compile(re.escape(path) + r":\d+:\d+: key 'dp'"), "expected a number", "fine")
    path = env.variant("type_list.yaml", "  size: [0.1, 0.05]", "  size: 0.1")
    expect_bad_input(env, [path], "'tank.size'", "list of 2 numbers")
    path = env.variant("type_bool.yaml", "  wall_layers: 3", "  wall_layers: 3\n  open_top: maybe")
    expect_bad_input(env, [path], "'tank.open_top'", "true or false")
    expect_bad_input(env, [env.tiny, "--set", "tank.wall_layers=2.5"], "'tank.wall_layers'", "integer")
    expect_bad_input(env, [env.tiny, "--set", "kernel=gaussian"], "'kernel'", "wendland_c2")


@test
def bad_missing_required_key(env):
    path = env.variant("no_dp.yaml", "dp: 0.005\n", "")
    expect_bad_input(env, [path], path, "'dp'", "required")
    path = env.variant("no_tank.yaml", "tank:\n  origin: [0, 0]\n  size: [0.1, 0.05]\n  wall_layers: 3\n", "")
    expect_bad_input(env, [path], path, "'tank'", "required")
    path = env.variant("no_name.yaml", "name: tiny_2d\n", "")
    expect_bad_input(env, [path], path, "'name'", "required")


@test
def bad_dp_not_positive(env):
    path = env.variant("dp0.yaml", "dp: 0.005", "dp: 0")
    expect_bad_input(env, [path], re.compile(re.escape(path) + r":\d+:\d+: key 'dp'"), "> 0")
    expect_bad_input(env, [env.tiny, "--set", "dp=-0.005"], "'dp'", "--set dp=-0.005", "> 0")


@test
def bad_negative_density(env):
    path = env.variant("rho.yaml", "  density: 1000", "  density: -1000")
    expect_bad_input(env, [path], path, "'fluid.density'", "> 0")


@test
def bad_negative_viscosity(env):
    path = env.variant("mu.yaml", "  viscosity: 0.001", "  viscosity: -0.001")
    expect_bad_input(env, [path], path, "'fluid.viscosity'", ">= 0")


@test
def bad_fluid_outside_tank(env):
    path = env.variant("outside.yaml", "    max: [0.05, 0.03]", "    max: [0.15, 0.03]")
    expect_bad_input(env, [path], path, "fluid_blocks[0]", "outside the tank")


@test
def bad_solid_outside_tank(env):
    path = env.write_case("solid_out.yaml", env.tiny_text() +
                          "solids:\n  - name: post\n    min: [0.08, 0]\n    max: [0.12, 0.02]\n")
    expect_bad_input(env, [path], path, "solids[0]", "outside the tank")


@test
def bad_floating_solids(env):
    """A floating solid without its mass, with both density and mass, with a degree of freedom the
    case has not, a contact deeper than dp/2, a body probe on a solid that does not float: exit 2,
    naming the key and why."""
    solid = "solids:\n  - name: raft\n    min: [0.06, 0.02]\n    max: [0.09, 0.03]\n    motion: floating\n"
    for name, extra, key, why in (
            ("no_mass.yaml", "", "solids[0]", "needs its density"),
            ("two_masses.yaml", "    density: 500\n    mass: 2\n", "solids[0]", "one of them"),
            ("bad_dof.yaml", "    density: 500\n    free: [z]\n", "'solids[0].free'", "'z' is not one of: x, y, rz"),
            ("bad_contact.yaml", "    density: 500\n    contact: {penetration: 0.01}\n", "'solids[0].contact.penetration'", "at most dp/2"),
            ("static_probe.yaml", "    density: 500\n  - name: post\n    min: [0.095, 0]\n    max: [0.1, 0.01]\n"
             "probes:\n  - name: p\n    type: body\n    solid: post\n", "'probes[0].solid'", "does not float")):
        path = env.write_case(name, env.tiny_text() + solid + extra)
        expect_bad_input(env, [path], path, key, why)


@test
def bad_fluid_overlaps_solid(env):
    path = env.write_case("overlap.yaml", env.tiny_text() +
                          "solids:\n  - name: post\n    min: [0.04, 0]\n    max: [0.06, 0.02]\n")
    expect_bad_input(env, [path], path, "solids[0]", "post", "overlaps a fluid block")


@test
def bad_zero_particles(env):
    # A block between two rows of site centres holds no particle; and no fluid at all.
    path = env.variant("thin.yaml", "  - min: [0, 0]\n    max: [0.05, 0.03]",
                       "  - min: [0.0051, 0]\n    max: [0.0074, 0.03]")
    expect_bad_input(env, [path], path, "no fluid particles")
    expect_bad_input(env, [path], path, "no fluid particles", command="info")
    expect_bad_input(env, [env.tiny, "--set", "fluid_blocks=[]"], "'fluid_blocks'", "no fluid")


@test
def bad_set_syntax(env):
    expect_bad_input(env, [env.tiny, "--set", "dp"], "--set 'dp'", "key.path=value")
    expect_bad_input(env, [env.tiny, "--set", "dp.x=1"], "--set 'dp.x=1'", "not a map")


# ---- bad input: command-line options ------------------------------------------------------------

@test
def bad_cli_options(env):
    expect_bad_input(env, [env.tiny, "--devices", "0"], "--devices 0", "at least 1")
    expect_bad_input(env, [env.tiny, "--steps", "-1"], "--steps -1", ">= 0")
    expect_bad_input(env, [env.tiny, "--backend", "opencl"], "--backend opencl", "'cpu' or 'cuda'")
    expect_bad_input(env, [env.tiny, "--until", "-1"], "--until -1", "> 0")
    expect_bad_input(env, [env.tiny, "--threads", "-2"], "--threads -2", ">= 0")
    expect_bad_input(env, [env.tiny, "--checkpoint-every", "-5"], "--checkpoint-every -5", ">= 0")
    expect_bad_input(env, [env.tiny, "--devices", "50"], "--devices 50", "at most")
    expect_bad_input(env, [env.tiny, "--steps", "many"], "spate: error:", "--steps", parsed=False)
    expect_bad_input(env, [env.tiny, "--no-such-option"], "spate: error:", "--no-such-option", parsed=False)
    expect_bad_input(env, [env.tiny, "--devices", "0"], "--devices 0", "at least 1", command="info")
    expect_bad_input(env, [env.tiny, "--restart", env.path("missing.h5")], "missing.h5")
    p = env.run("frobnicate")
    check(p.returncode == 2, f"unknown subcommand: exit {p.returncode}")


@test
def help_lists_exit_codes(env):
    p = env.run("--help")
    check(p.returncode == 0, f"exit {p.returncode}")
    for needle in ["Exit codes", "0 done", "2 bad input", "3 the run went unstable", "run", "info", "compare"]:
        check(needle in p.stdout, f"'{needle}' not in spate --help")


# ---- info ---------------------------------------------------------------------------------------

@test
def info_json(env):
    p = env.run("info", env.tiny, "--json")
    check(p.returncode == 0, f"exit {p.returncode}")
    j = json.loads(p.stdout)
    for key in ["case", "dimensions", "particles", "dp", "smoothing_length", "sound_speed",
                "sound_speed_automatic", "dt", "dt_adaptive", "cells", "bytes_per_particle",
                "memory_bytes", "backend"]:
        check(key in j, f"info --json lacks '{key}'")
    check(j["case"] == "tiny_2d" and j["dimensions"] == 2, "case name or dimensions")
    # 20 x 10 interior sites, 10 x 6 of water; walls: 26 x 13 sites (3 layers, open top) minus 200.
    check(j["particles"] == {"fluid": 60, "wall": 138, "total": 198}, f"particles: {j['particles']}")
    check(abs(j["dp"] - 0.005) < 1e-12, "dp")
    check(abs(j["smoothing_length"] - 1.3 * 0.005) < 1e-8, "h = 1.3 dp")
    c0 = 10 * (9.81 * 0.03) ** 0.5  # automatic: 10 sqrt(g H), H = 0.03 m
    check(abs(j["sound_speed"] - c0) < 1e-5 * c0 and j["sound_speed_automatic"] is True, f"c0 {j['sound_speed']} vs {c0}")
    check(j["dt_adaptive"] is True and 0 < j["dt"] < 0.2 * 0.0065 / c0 * 1.0001, f"dt {j['dt']}")
    check(len(j["cells"]) == 3 and j["cells"][2] == 1, f"cells {j['cells']}")
    check(j["memory_bytes"] == j["bytes_per_particle"] * 198, "memory = bytes/particle x particles")
    # Materials: the fluid (index 0) with its properties, then the tank.
    m = j.get("materials", [])
    check([e["kind"] for e in m] == ["fluid", "tank"] and m[0]["index"] == 0 and m[1]["index"] == 1, f"materials {m}")
    check(m[0]["rest_density"] == 1000 and m[0]["tait_exponent"] == 7 and abs(m[0]["sound_speed"] - c0) < 1e-5 * c0,
          f"fluid material {m[0]}")
    check(abs(m[0]["particle_mass"] / (1000 * 0.005 ** 2) - 1) < 1e-6 and abs(m[0]["viscosity"] / 0.001 - 1) < 1e-6, f"fluid material {m[0]}")
    check(not os.listdir(env.work), "info wrote files")
    # SPS turbulence: off by default; on, its constants, and its fields' bytes (the stress's diagonal
    # and shear, 2 + 2 floats in 2D, and the eddy viscosity) only in its runs.
    check(j["turbulence"] == {"model": "none"}, f"turbulence {j.get('turbulence')}")
    p = env.run("info", env.tiny, "--json", "--set", "turbulence.model=sps")
    s = json.loads(p.stdout)
    check(s["turbulence"] == {"model": "sps", "smagorinsky": 0.12, "isotropic": 0.0066}, f"turbulence {s['turbulence']}")
    check(s["bytes_per_particle"] - j["bytes_per_particle"] == 20, f"SPS bytes {s['bytes_per_particle']} vs {j['bytes_per_particle']}")
    p = env.run("info", env.tiny, "--set", "turbulence.model=les")
    check(p.returncode == 2 and "turbulence.model" in p.stderr, f"bad model: exit {p.returncode}, {p.stderr}")

    p = env.run("info", env.tiny, "--json", "--set", "fluid.sound_speed=30", "--set", "time.dt=1e-4",
                "--set", "tank.open_top=false")
    j = json.loads(p.stdout)
    check(j["sound_speed"] == 30 and j["sound_speed_automatic"] is False, "sound speed from the case")
    check(j["dt"] == 1e-4 and j["dt_adaptive"] is False, "fixed dt")
    check(j["particles"]["wall"] == 26 * 16 - 200, f"closed top walls: {j['particles']}")

    p = env.run("info", env.tiny)
    check(p.returncode == 0 and "60 fluid" in p.stdout and "138 wall" in p.stdout, "text info")
    check(re.search(r"0\s+water\s+fluid: rho0 = 1000 kg/m3", p.stdout) and re.search(r"1\s+tank\s+tank walls", p.stdout),
          f"text info lists the materials:\n{p.stdout}")


@test
def bench_json_reports_the_build(env):
    """spate bench --json says what the CPU code was built for and whether the run's pair loop is
    a vectorised one (issue 36): gamma = 7 takes the vector loop, another exponent the scalar one."""
    levels = {"x86-64-v4 (AVX-512)": 512, "x86-64-v3 (AVX2)": 256, "x86-64-v2 (SSE4.2)": 128, "x86-64 (SSE2)": 128}
    for gamma, loop in ((7, "vector"), (1.4, "scalar")):
        p = env.run("bench", env.tiny, "--steps", "2", "--threads", "1", "--json", "--set", f"fluid.tait_exponent={gamma}")
        check(p.returncode == 0, f"exit {p.returncode}")
        cpu = json.loads(p.stdout).get("cpu", {})
        check(set(cpu) == {"model", "isa", "vector_bits", "arch_flags", "pair_loop"}, f"cpu block {cpu}")
        check(cpu["pair_loop"] == loop, f"tait_exponent {gamma}: pair loop {cpu['pair_loop']}, expected {loop}")
        check(levels.get(cpu["isa"]) == cpu["vector_bits"], f"isa {cpu['isa']} with {cpu['vector_bits']} bits")
        check(cpu["model"] != "" and isinstance(cpu["arch_flags"], str), f"model and flags {cpu}")
        if platform.machine() == "x86_64" and "avx512bw" in open("/proc/cpuinfo").read() and "-march=native" in cpu["arch_flags"]:
            check(cpu["isa"] == "x86-64-v4 (AVX-512)", f"a native build on an AVX-512 machine reports {cpu['isa']}")
    p = env.run("bench", env.tiny, "--steps", "2", "--threads", "1")
    check(p.returncode == 0 and re.search(r"CPU code x86-64[^,]*, (vector|scalar) pair loop", p.stdout), "text bench names the build")


@test
def bench_times_each_pass(env):
    """spate bench --pass-times --json reports, per device, the seconds of each pass of the step
    (issue 34): the passes every step runs are there and took time, none that the case does not
    run, and together they fit in the run's time; without the flag, no pass times."""
    p = env.run("bench", env.tiny, "--steps", "3", "--threads", "1", "--json", "--pass-times")
    check(p.returncode == 0, f"exit {p.returncode}: {p.stderr}")
    j = json.loads(p.stdout)
    passes = j.get("pass_seconds")
    check(isinstance(passes, list) and len(passes) == 1, f"one device's passes: {passes}")
    every_step = {"predict", "rebuild", "equation_of_state", "wall_state", "fluid_rates", "halo_refresh", "correct", "time_step"}
    check(every_step <= set(passes[0]), f"passes {sorted(passes[0])}")
    check(not set(passes[0]) & {"sps_stress", "heat_rates", "shifting", "surface_tension"}, f"passes the case does not run: {sorted(passes[0])}")
    check(all(v > 0 for v in passes[0].values()), f"times {passes[0]}")
    check(sum(passes[0].values()) <= j["wall_seconds"], f"passes {sum(passes[0].values())} s within the run's {j['wall_seconds']} s")
    p = env.run("bench", env.tiny, "--steps", "2", "--threads", "1", "--json")
    check(p.returncode == 0 and "pass_seconds" not in json.loads(p.stdout), "no pass times unless asked")
    p = env.run("bench", env.tiny, "--steps", "2", "--threads", "1", "--pass-times")
    check(p.returncode == 0 and re.search(r"device 0 passes \(s over \d+ steps\): .*fluid_rates", p.stdout), f"text bench lists passes:\n{p.stdout}")
    # The environment variables spate reads are input: a bad value exits 2 naming it.
    for name, value in (("SPATE_PASS_TIMERS", "yes"), ("SPATE_GPU_PAIR_LOOP", "threads"), ("SPATE_CUDA_HALO_LINK", "peer")):
        os.environ[name] = value
        try:
            p = env.run("run", env.tiny, "--steps", "1", "--out", "bad-env")
        finally:
            del os.environ[name]
        check(p.returncode == 2 and name in p.stderr, f"{name}={value}: exit {p.returncode}: {p.stderr}")


@test
def info_shipped_cases(env):
    for name in sorted(os.listdir(env.shipped)):
        if not name.endswith(".yaml"):
            continue
        p = env.run("info", os.path.join(env.shipped, name), "--json")
        check(p.returncode == 0, f"{name}: exit {p.returncode}")
        j = json.loads(p.stdout)
        check(j["particles"]["fluid"] > 0 and j["particles"]["total"] == j["particles"]["fluid"] + j["particles"]["wall"],
              f"{name}: {j['particles']}")


# ---- compare ------------------------------------------------------------------------------------

def final_checkpoint(env, out, steps):
    path = os.path.join(out, "checkpoints", f"checkpoint_step_{steps:08d}.h5")
    check(os.path.isfile(path), f"no final checkpoint {path}")
    with open(os.path.join(out, "summary.json")) as f:
        summary = json.load(f)
    check(summary["exit_status"] == "done" and summary["exit_code"] == 0, f"summary: {summary.get('exit_status')}")
    check(summary["last_checkpoint"] == path, f"summary last_checkpoint {summary['last_checkpoint']}")
    return path


@test
def compare_checkpoints(env):
    runs = {}
    for label, steps in [("a", 6), ("b", 6), ("c", 7)]:
        out = env.path(label)
        p = env.run("run", env.tiny, "--steps", str(steps), "--out", out, "--quiet")
        check(p.returncode == 0, f"run {label}: exit {p.returncode}")
        runs[label] = final_checkpoint(env, out, steps)
    p = env.run("compare", runs["a"], runs["b"])
    check(p.returncode == 0 and "MATCH" in p.stdout, "two identical runs must compare equal (exit 0)")
    check(re.search(r"^x\s+0\s", p.stdout, re.M), "the largest difference per field is printed")
    p = env.run("compare", runs["a"], runs["a"])
    check(p.returncode == 0, "a checkpoint equals itself")
    p = env.run("compare", runs["a"], runs["c"])
    check(p.returncode == 1 and "DIFFERENT" in p.stdout, f"6 vs 7 steps must differ (exit 1), got {p.returncode}")
    worst = {m.group(1): float(m.group(2)) for m in re.finditer(r"^(\w+)\s+([-+0-9.eE]+|inf)\s+\d+$", p.stdout, re.M)}
    check(worst.get("y", 0) > 0, f"positions differ after one more step: {worst}")
    p = env.run("compare", runs["a"], runs["c"], "--tolerance", "1e9")
    check(p.returncode == 0, f"within a huge tolerance: exit {p.returncode}")
    p = env.run("compare", runs["a"], runs["b"], "--tolerance", "-1")
    check(p.returncode == 2 and "--tolerance -1" in p.stderr, f"negative tolerance: exit {p.returncode}")
    # Tolerances as fractions of each field's scale (dp, c0, rho0, ...; material exact), printed per field.
    p = env.run("compare", runs["a"], runs["c"], "--scaled-tolerance", "1e-12")
    check(p.returncode == 1 and "DIFFERENT" in p.stdout, f"one step apart, scaled 1e-12: exit {p.returncode}")
    p = env.run("compare", runs["a"], runs["c"], "--scaled-tolerance", "10")
    check(p.returncode == 0 and re.search(r"^material\s+0\s+\d+\s+0$", p.stdout, re.M), f"scaled 10: exit {p.returncode}\n{p.stdout}")
    p = env.run("compare", runs["a"], runs["b"], "--scaled-tolerance", "-1")
    check(p.returncode == 2 and "--scaled-tolerance -1" in p.stderr, f"negative scaled tolerance: exit {p.returncode}")
    p = env.run("compare", runs["a"], env.path("missing.h5"))
    check(p.returncode == 2 and "missing.h5" in p.stderr, f"missing checkpoint: exit {p.returncode}")
    not_h5 = env.write_case("not_a_checkpoint.yaml", "x: 1\n")
    p = env.run("compare", runs["a"], not_h5)
    check(p.returncode == 2 and "not_a_checkpoint.yaml" in p.stderr, f"not a checkpoint: exit {p.returncode}")


@test
def compare_split_independent(env):
    # The same run on one and on two device slabs: bit-identical checkpoints.
    paths = []
    for devices in (1, 2):
        out = env.path(f"d{devices}")
        p = env.run("run", env.tiny, "--steps", "10", "--devices", str(devices), "--out", out, "--quiet")
        check(p.returncode == 0, f"--devices {devices}: exit {p.returncode}")
        paths.append(final_checkpoint(env, out, 10))
    p = env.run("compare", *paths)
    check(p.returncode == 0, "1 and 2 devices must give bit-identical results")


@test
def growth_fits_a_probe_and_refuses_bad_input(env):
    # spate growth: a growing and a decaying mode, 0.004 e^(1.2 t) + 0.0035 e^(-1.2 t), written as an
    # interface probe's CSV, fitted back (docs/cli.md); a missing column or file is bad input.
    folder = tempfile.mkdtemp()  # outside the working folder, which bad input must leave untouched
    csv = os.path.join(folder, "amplitude.csv")
    with open(csv, "w") as f:
        f.write("time[s],step,amplitude[m],top[m],bottom[m]\n")
        for k in range(80):
            t = 0.02 * k
            a = 0.004 * math.exp(1.2 * t) + 0.0035 * math.exp(-1.2 * t)
            f.write(f"{t},{k},{a!r},{0.5 + a!r},{0.5 - a!r}\n")
    p = env.run("growth", csv, "--until", "0.03", "--json")
    check(p.returncode == 0, f"exit {p.returncode}")
    fit = json.loads(p.stdout)
    check(abs(fit["rate"] - 1.2) < 1e-5, f"rate {fit['rate']}, expected 1.2")
    check(fit["to"] < 1.6, f"the fit ran past the amplitude limit: to {fit['to']}")
    expect_bad_input(env, [csv, "--column", "height"], "no column 'height'", "columns: amplitude, top, bottom", command="growth")
    expect_bad_input(env, [os.path.join(folder, "missing.csv")], "missing.csv", "cannot be read", command="growth")
    shutil.rmtree(folder)


@test
def shifting_split_independent(env):
    # Particle shifting (a neighbour pass whose result moves the particles) on one and on three
    # device slabs: bit-identical checkpoints; and it moves them (not the run without it). The same
    # with the volume-consistent density (the shifts cross the slab faces in a halo refresh, then
    # change the densities), which changes the particles again, and with the velocity correction
    # (the velocity gradient from the ghosts' velocities), which changes them too.
    paths = {}
    variants = {"plain": [], "consistent": ["shifting.volume_consistent=true"], "velocity": ["shifting.correct_velocity=true"]}
    for devices, shifting, variant in ((1, "true", "plain"), (3, "true", "plain"), (1, "false", "plain"), (1, "true", "consistent"),
                                       (3, "true", "consistent"), (1, "true", "velocity"), (3, "true", "velocity")):
        out = env.path(f"shift{devices}{shifting}{variant}")
        sets = [a for key in variants[variant] for a in ("--set", key)]
        p = env.run("run", env.tiny, "--steps", "20", "--devices", str(devices), "--out", out, "--quiet",
                    "--set", f"shifting.enabled={shifting}", *sets)
        check(p.returncode == 0, f"--devices {devices}, shifting {shifting}, {variant}: exit {p.returncode}")
        paths[devices, shifting, variant] = final_checkpoint(env, out, 20)
    for variant in variants:
        p = env.run("compare", paths[1, "true", variant], paths[3, "true", variant], "--tolerance", "0")
        check(p.returncode == 0, f"with shifting ({variant}), 1 and 3 devices must give bit-identical results")
    p = env.run("compare", paths[1, "true", "plain"], paths[1, "false", "plain"], "--tolerance", "0")
    check(p.returncode != 0, "shifting must change the particles")
    for variant in ("consistent", "velocity"):
        p = env.run("compare", paths[1, "true", "plain"], paths[1, "true", variant], "--tolerance", "0")
        check(p.returncode != 0, f"shifting's {variant} option must change the particles")


@test
def closed_volume_scalings_in_summary(env):
    # density.closed_volume: summary.json counts the steps after which the densities were scaled
    # back (at most one a step); a case without the key has no such field.
    out = env.path("closed_volume")
    p = env.run("run", os.path.join(env.shipped, "cylinder_flow_2d.yaml"), "--steps", "60", "--out", out, "--quiet",
                "--set", "dp=0.02", "--set", "output.interval=0")
    check(p.returncode == 0, f"cylinder_flow_2d at dp 0.02: exit {p.returncode}: {p.stderr}")
    with open(os.path.join(out, "summary.json")) as f:
        n = json.load(f).get("closed_volume_scalings")
    check(isinstance(n, int) and 0 < n <= 60, f"closed_volume_scalings {n} in 60 steps")
    tiny = env.path("no_closed_volume")
    p = env.run("run", env.tiny, "--steps", "2", "--out", tiny, "--quiet")
    with open(os.path.join(tiny, "summary.json")) as f:
        check("closed_volume_scalings" not in json.load(f), "a run without density.closed_volume reports no scalings")


@test
def compare_restart_bit_identical(env):
    # 10 steps in one go against 5 steps + a restart for 5 more (on two devices).
    p = env.run("run", env.tiny, "--steps", "10", "--out", env.path("straight"), "--quiet")
    check(p.returncode == 0, f"exit {p.returncode}")
    straight = final_checkpoint(env, env.path("straight"), 10)
    p = env.run("run", env.tiny, "--steps", "5", "--out", env.path("first"), "--quiet")
    half = final_checkpoint(env, env.path("first"), 5)
    p = env.run("run", env.tiny, "--restart", half, "--steps", "5", "--devices", "2", "--out", env.path("second"), "--quiet")
    check(p.returncode == 0, f"restart: exit {p.returncode}")
    resumed = final_checkpoint(env, env.path("second"), 10)
    p = env.run("compare", straight, resumed)
    check(p.returncode == 0, "a restarted run must be bit-identical to an uninterrupted one")
    # A checkpoint of another case is bad input.
    other = os.path.join(env.shipped, "dam_break_2d.yaml")
    p = env.run("run", other, "--restart", half, "--steps", "1", "--out", env.path("wrong"), "--quiet")
    check(p.returncode == 2 and "checkpoint holds" in p.stderr, f"restart with another case: exit {p.returncode}")
    check_refused(env.path("wrong"), p.stderr)


def write_box_stl(path, lo, hi):
    """A closed box (12 triangles, outward normals) as ASCII STL."""
    corner = lambda i: [hi[a] if (i >> a) & 1 else lo[a] for a in range(3)]
    faces = [(0, 2, 6, 4), (1, 5, 7, 3), (0, 4, 5, 1), (2, 3, 7, 6), (0, 1, 3, 2), (4, 6, 7, 5)]
    with open(path, "w") as f:
        f.write("solid box\n")
        for q in faces:
            for tri in ((q[0], q[2], q[1]), (q[0], q[3], q[2])):
                f.write("facet normal 0 0 0\nouter loop\n")
                for v in tri:
                    f.write("vertex {} {} {}\n".format(*corner(v)))
                f.write("endloop\nendfacet\n")
        f.write("endsolid box\n")


@test
def restart_with_changed_mesh(env):
    # A case whose solid is a mesh next to it: a restart from its checkpoint works while the mesh is
    # the same, and is refused (exit 2, the reason) once the mesh file has changed.
    folder = env.path("case")
    os.makedirs(folder)
    mesh = os.path.join(folder, "block.stl")
    write_box_stl(mesh, [0.07, 0.0, -0.01], [0.09, 0.02, 0.01])
    case = os.path.join(folder, "tiny_mesh.yaml")
    with open(case, "w") as f:
        f.write(env.tiny_text() + "solids:\n  - {name: block, mesh: block.stl}\n")
    p = env.run("run", case, "--steps", "4", "--out", env.path("first"), "--quiet")
    if p.returncode == 2 and "reads no meshes" in p.stderr:
        print("  (built without mesh support: skipped)")
        return
    check(p.returncode == 0, f"exit {p.returncode}")
    half = final_checkpoint(env, env.path("first"), 4)
    p = env.run("run", case, "--restart", half, "--steps", "2", "--out", env.path("second"), "--quiet")
    check(p.returncode == 0, f"restart with the same mesh: exit {p.returncode}")
    write_box_stl(mesh, [0.065, 0.0, -0.01], [0.09, 0.02, 0.01])
    p = env.run("run", case, "--restart", half, "--steps", "2", "--out", env.path("third"), "--quiet")
    check(p.returncode == 2 and "mesh file the case names has changed" in p.stderr, f"restart with a changed mesh: exit {p.returncode}")
    check_refused(env.path("third"), p.stderr)


# ---- instability --------------------------------------------------------------------------------

@test
def second_run_into_a_busy_folder(env):
    # A run holds its output folder: a second `spate run` into it while the first is writing is
    # refused (exit 2) and writes nothing there (the summary.json is the first run's); once the
    # first has ended the folder is free again.
    out = env.path("busy")
    case = os.path.join(env.shipped, "dam_break_2d.yaml")
    first = subprocess.Popen([env.spate, "run", case, "--steps", "5000", "--out", out, "--quiet", "--threads", "1"],
                             cwd=env.work, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 60
        while not os.path.exists(os.path.join(out, "case.yaml")) and first.poll() is None and time.monotonic() < deadline:
            time.sleep(0.05)
        check(first.poll() is None, "the first run ended before the second could start: lengthen it")
        p = env.run("run", env.tiny, "--out", out, "--quiet")
        check(p.returncode == 2, f"second run: exit {p.returncode}, expected 2")
        check("another spate run is writing into this folder" in p.stderr and out in p.stderr,
              f"the refusal does not say why: {p.stderr.strip()}")
        check(not os.path.exists(os.path.join(out, "summary.json")), "the refused run wrote a summary.json into the busy folder")
        check(first.poll() is None, "the first run must go on (lengthen it if it ended by itself)")
    finally:
        stdout, stderr = first.communicate(timeout=300)
    check(first.returncode == 0, f"the first run: exit {first.returncode}: {stderr.strip()}")
    with open(os.path.join(out, "summary.json")) as f:
        s = json.load(f)
    check(s["exit_status"] == "done" and s["final_step"] == 5000 and s["case"] == "dam_break_2d",
          f"the first run's summary: {s['exit_status']} {s.get('final_step')} {s.get('case')}")
    p = env.run("run", env.tiny, "--steps", "5", "--out", out, "--quiet")
    check(p.returncode == 0, f"a run into the folder once it is free: exit {p.returncode}")


@test
def unstable_run(env):
    # The 2D dam break with a fixed step 10x above its CFL limit blows up within a few steps.
    out = env.path("unstable")
    case = os.path.join(env.shipped, "dam_break_2d.yaml")
    p = env.run("run", case, "--set", "time.dt=0.0005", "--steps", "200", "--checkpoint-every", "1",
                "--out", out, "--quiet")
    check(p.returncode == 3, f"exit {p.returncode}, expected 3 (unstable)")
    check("unstable" in p.stderr, "stderr does not say the run went unstable")
    with open(os.path.join(out, "summary.json")) as f:
        s = json.load(f)
    check(s["exit_status"] == "unstable" and s["exit_code"] == 3, f"summary: {s['exit_status']} {s['exit_code']}")
    m = re.search(r"step (\d+), t = ([0-9.eE+-]+) s: particle (\d+) ", s["message"])
    check(m, f"message does not name step, time and particle: {s['message']}")
    step = int(m.group(1))
    check(abs(float(m.group(2)) - step * 0.0005) < 1e-9, "time = step x dt")
    check(s["final_step"] == step, "final_step is the failing step")
    # Diagnostic snapshot of the failing state.
    diag = os.path.join(out, "diagnostic", f"step_{step:08d}.vtm")
    check(os.path.isfile(diag), f"no diagnostic snapshot {diag}")
    check(os.path.isfile(os.path.join(out, "diagnostic", f"step_{step:08d}", "slab_0.vtp")), "no diagnostic piece")
    # The last good checkpoint is the step before, and readable.
    good = s["last_checkpoint"]
    check(good.endswith(f"checkpoint_step_{step - 1:08d}.h5") and os.path.isfile(good), f"last good checkpoint {good}")
    check(good in s["message"] and good in p.stderr, "the message names the last good checkpoint")
    p = env.run("compare", good, good)
    check(p.returncode == 0, "the last good checkpoint must be readable")
    # Restarting from it replays the failure exactly: same step, time and particle (a debugging aid).
    p = env.run("run", case, "--set", "time.dt=0.0005", "--restart", good, "--steps", "200", "--out",
                env.path("replay"), "--quiet")
    check(p.returncode == 3, f"replay from the last good checkpoint: exit {p.returncode}")
    check(m.group(0) in p.stderr, f"the replay fails differently: {p.stderr.strip()}")


@test
def unstable_kinds(env):
    # The other two kinds of instability: a particle thrown out of the domain, and NaN (an absurd
    # sound speed overflows the Tait coefficient). Each: exit 3, the particle named, a diagnostic.
    case = os.path.join(env.shipped, "dam_break_2d.yaml")
    for label, setting, needle in [("left", "time.dt=0.01", "left the domain along"),
                                   ("nan", "fluid.sound_speed=1e20", "non-finite")]:
        out = env.path(label)
        p = env.run("run", case, "--set", setting, "--steps", "50", "--out", out, "--quiet")
        check(p.returncode == 3, f"{setting}: exit {p.returncode}, expected 3")
        with open(os.path.join(out, "summary.json")) as f:
            s = json.load(f)
        check(s["exit_status"] == "unstable", f"{setting}: summary {s['exit_status']}")
        check(re.search(r"step \d+, t = \S+ s: particle \d+ .*" + needle, s["message"]), f"{setting}: {s['message']}")
        check(any(n.endswith(".vtm") for n in os.listdir(os.path.join(out, "diagnostic"))), "no diagnostic snapshot")


def main(tests=TESTS, env_class=None):
    """The command line of a test driver: this file's tests, or another driver's (post_tests.py,
    robustness_tests.py with its own Env)."""
    env_class = env_class or Env
    ap = argparse.ArgumentParser()
    ap.add_argument("--spate", required=True)
    ap.add_argument("--cases", required=True, help="tests/cases")
    ap.add_argument("--shipped", required=True, help="the shipped cases/ folder")
    ap.add_argument("--work", required=True)
    ap.add_argument("--list", action="store_true")
    ap.add_argument("names", nargs="*")
    args = ap.parse_args()
    if args.list:
        print("\n".join(tests))
        return 0
    failed = []
    for name in args.names or list(tests):
        if name not in tests:
            print(f"unknown test {name}")
            return 2
        begin = time.monotonic()
        try:
            tests[name](env_class(args, name))
            print(f"PASS {name} ({time.monotonic() - begin:.1f} s)")
        except (Failure, subprocess.TimeoutExpired, json.JSONDecodeError, FileNotFoundError, KeyError) as e:
            print(f"FAIL {name}: {type(e).__name__}: {e}")
            failed.append(name)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
