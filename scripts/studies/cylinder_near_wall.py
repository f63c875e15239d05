"""The fluid next to the cylinder of cases/cylinder_flow_2d.yaml, from a run's saved steps: what the
fluid's own fields say the drag is, set beside the force its particles exert on the wall's, angle by
angle (docs/studies/cylinder-flow.md, "Where the drag goes"). For each saved step in [t0, t1]:
- the drag from the fields: least-squares fits, over the fluid particles within `delta` of the
  surface, of u_t = sum_k (r - R) (a_k cos k th + b_k sin k th) + (r - R)^2 (...) + (...) (a slip
  term) and p = sum_k (...) + (r - R) (...), Fourier order 6; then the viscous drag
  -pi R mu b_1 (the sin-th part of du_t/dr at r = R) and the pressure drag -pi R c_1 (p's cos-th
  part at r = R), as c_D (without the drive's push);
- per 30-degree sector (th from the rear, counter-clockwise): the tangential (counter-clockwise)
  viscous force of the fluid on the cylinder's particles, the pair term the solver uses (eq. 8 with
  Adami's wall velocity as the saved step holds it), against mu du_t/dr times the sector's arc from
  a quadratic fit within 0.02 m; the mean and least pressure within 3 dp of the surface; the mean
  gap from the surface to the five nearest fluid particles, in dp; the SPH shear stress across the
  lines 1, 2 and 4 dp from the surface (the tangential viscous pair forces that the fluid above the
  line receives from the fluid below it, per sector, by the pair midpoint's angle); and how evenly
  the fluid within 6 dp of the surface is spread: its particle count and the mean and tenth
  percentile of the distance to each particle's nearest neighbour, in dp (clumps of the tensile
  instability show as small distances and few particles).
The spacing, smoothing ratio, density and viscosity come from the run's own case.yaml (Wendland
kernel only, the case's).
Usage: /usr/bin/python3 scripts/studies/cylinder_near_wall.py RUN [T0 T1]   (T0, T1: 2, 3 s)
"""
import sys
from pathlib import Path

import numpy as np
import yaml
from scipy.spatial import cKDTree

sys.path.insert(0, str(Path(__file__).parent))
from run_output import saved_steps, snapshot_arrays  # noqa: E402

R, CENTRE, U = 0.05, np.array([0.2, 0.2]), 0.2  # the case's cylinder and bulk velocity
FOURIER, SECTORS = 6, 12
LINES = (1, 2, 4)  # dp from the surface: the lines across which the SPH shear stress is summed
FLUID, CYLINDER = 0, 2  # the saved `kind` of fluid and of the case's one solid


def wendland_gradient_norm(h, dp):
    """kernel_norm over the lattice's second moment (physics/kernels.hpp lattice_gradient_moment)."""
    norm = 7 / (4 * np.pi * h * h)
    n = int(2 * h / dp) + 1
    i, j = np.meshgrid(np.arange(-n, n + 1), np.arange(-n, n + 1))
    r = np.hypot(i, j) * dp
    q = r / h
    inside = (q < 2) & (r > 0)
    F = -5 * norm * (1 - q[inside] / 2) ** 3 / h ** 2
    return norm / np.sum(-dp * dp * (i[inside] * dp) ** 2 * F)


def fourier(th):
    cols = [np.ones_like(th)]
    for k in range(1, FOURIER + 1):
        cols += [np.cos(k * th), np.sin(k * th)]
    return np.stack(cols, 1)  # column 1: cos th, column 2: sin th


def fluid_side_drag(r, th, ut, p, delta, mu):
    """Viscous and pressure drag [N/m] from the fits (column 2 of u_t's first block: sin th times
    (r - R), i.e. du_t/dr's sin-th part; column 1 of p's: its cos-th part at r = R)."""
    s = r - R < delta
    y, Fo = r[s] - R, fourier(th[s])
    cu = np.linalg.lstsq(np.hstack([Fo * y[:, None], Fo * (y * y)[:, None], Fo]), ut[s], rcond=None)[0]
    cp = np.linalg.lstsq(np.hstack([Fo, Fo * y[:, None]]), p[s], rcond=None)[0]
    return -np.pi * R * mu * cu[2], -np.pi * R * cp[1]


def laminar_force(xi, xj, vi, vj, rho_i, rho_j, h, gn, eta2, mu, m):
    """The laminar viscous force [N/m] on particle(s) i from j, eq. 8 as the solver sums it
    (fluid_pair_terms' laminar term, Wendland kernel): mu (V_i^2 + V_j^2) r^2 F / (r^2 + eta^2)
    (v_i - v_j), with grad W = F (x_i - x_j)."""
    e = xi - xj
    r2 = (e * e).sum(-1)
    F = -5 * gn * np.maximum(1 - np.sqrt(r2) / h / 2, 0) ** 3 / h ** 2
    return (mu * ((m / rho_i) ** 2 + (m / rho_j) ** 2) * r2 * F / (r2 + eta2))[..., None] * (vi - vj)


def line_stresses(x, v, rho, kind, dp, h, gn, eta2, mu, m, out):
    """Adds to out[n, sector] the counter-clockwise tangential viscous force [N/m] that the fluid
    more than LINES[n] dp from the surface receives from the particles nearer to it, the cylinder's
    included (eq. 8's pairs, as the solver sums them, with the walls' no-slip velocity as saved),
    each pair counted in the sector of its midpoint."""
    d = x - CENTRE
    r = np.hypot(d[:, 0], d[:, 1])
    r = np.where(kind == CYLINDER, R - dp, r)  # the cylinder's particles lie below every line
    near = np.where(((kind == FLUID) | (kind == CYLINDER)) & (r < R + (max(LINES) + 3) * dp))[0]
    pairs = np.array(sorted(cKDTree(x[near]).query_pairs(2 * h)))
    i, j = near[pairs[:, 0]], near[pairs[:, 1]]
    on_i = laminar_force(x[i], x[j], v[i], v[j], rho[i], rho[j], h, gn, eta2, mu, m)
    mid = 0.5 * (x[i] + x[j]) - CENTRE
    t = np.stack([-mid[:, 1], mid[:, 0]], 1) / np.hypot(mid[:, 0], mid[:, 1])[:, None]
    along = (on_i * t).sum(1)  # on i; -along on j
    sec = sector_of(np.arctan2(mid[:, 1], mid[:, 0]))
    yi, yj = (r[i] - R) / dp, (r[j] - R) / dp
    for n, y in enumerate(LINES):
        cross = np.where((yi >= y) & (yj < y), along, 0.0) - np.where((yj >= y) & (yi < y), along, 0.0)
        out[n] += np.bincount(sec, weights=cross, minlength=SECTORS)


def sector_of(th):
    return (((th + np.pi) / (2 * np.pi) * SECTORS).astype(int)) % SECTORS


def analyse(run, t0, t1):
    case = yaml.safe_load((Path(run) / "case.yaml").read_text())
    if case.get("kernel", "wendland") != "wendland":
        sys.exit(f"{run}: the kernel is {case['kernel']}; this script knows the Wendland kernel only")
    dp, rho0, mu = case["dp"], case["fluid"]["density"], case["fluid"]["viscosity"]
    q = 0.5 * rho0 * U * U * 2 * R  # 1/2 rho U^2 D
    h = case.get("smoothing_ratio", 1.3) * dp
    gn, eta2, m = wendland_gradient_norm(h, dp), 0.01 * h * h, rho0 * dp * dp
    drag, steps = [], 0
    wall, shear, pmean, pmin, gap, count, nn_mean, nn_p10 = (np.zeros(SECTORS) for _ in range(8))
    lines = np.zeros((len(LINES), SECTORS))
    for t, step in saved_steps(Path(run)):
        if t < t0 - 1e-3 or t > t1 + 1e-3:
            continue
        x, a = snapshot_arrays(step, ["kind", "velocity", "density", "pressure"])
        x, v, rho, kind = x[:, :2], a["velocity"][:, :2], a["density"], a["kind"]
        f, w = np.where(kind == FLUID)[0], np.where(kind == CYLINDER)[0]
        d = x[f] - CENTRE
        r, th = np.hypot(d[:, 0], d[:, 1]), np.arctan2(d[:, 1], d[:, 0])
        ut = (-d[:, 1] * v[f, 0] + d[:, 0] * v[f, 1]) / r
        drag.append([fluid_side_drag(r, th, ut, a["pressure"][f], delta, mu) for delta in (0.015, 0.02, 0.03)])
        # The wall particles' viscous pair force, as the solver sums it (fluid_pair_terms' laminar term).
        tree = cKDTree(x[f])
        for b in w:
            js = f[tree.query_ball_point(x[b], 2 * h)]
            if len(js) == 0:
                continue
            force = laminar_force(x[b], x[js], v[b], v[js], rho[b], rho[js], h, gn, eta2, mu, m).sum(0)
            tb = np.arctan2(x[b, 1] - CENTRE[1], x[b, 0] - CENTRE[0])
            wall[sector_of(np.array([tb]))[0]] += force @ np.array([-np.sin(tb), np.cos(tb)])
        sec = sector_of(th)
        for k in range(SECTORS):
            s = (sec == k) & (r - R < 0.02)
            shear_k = np.polyfit(r[s] - R, ut[s], 2)[-2] if s.sum() > 3 else np.nan
            near = (sec == k) & (r - R < 3 * dp)
            shear[k] += mu * shear_k * 2 * np.pi * R / SECTORS
            pmean[k] += a["pressure"][f][near].mean()
            pmin[k] += a["pressure"][f][near].min()
            gap[k] += np.sort((r[sec == k] - R) / dp)[:5].mean()
        line_stresses(x, v, rho, kind, dp, h, gn, eta2, mu, m, lines)
        nn = cKDTree(x[f]).query(x[f], 2)[0][:, 1] / dp
        for k in range(SECTORS):
            s = (sec == k) & (r - R < 6 * dp)
            count[k] += s.sum()
            nn_mean[k] += nn[s].mean()
            nn_p10[k] += np.percentile(nn[s], 10)
        steps += 1
    if steps == 0:
        sys.exit(f"{run}: no saved step between {t0} and {t1} s")
    drag = np.array(drag).mean(0) / q
    print(f"{run} (D/dp = {2 * R / dp:g}), {steps} saved steps in [{t0:g}, {t1:g}] s")
    for delta, (cv, cp) in zip((0.015, 0.02, 0.03), drag):
        print(f"  from the fields within {delta} m: viscous c_D {cv:.3f}, pressure c_D {cp:.3f} (without the drive's push)")
    centres = np.degrees(-np.pi + 2 * np.pi * (np.arange(SECTORS) + 0.5) / SECTORS)
    rows = [("sector centre [deg]", centres, "{:7.0f}"), ("wall pair force [N/m]", wall / steps, "{:7.3f}"),
            ("mu du_t/dr x arc [N/m]", shear / steps, "{:7.3f}"), ("mean p, 3 dp [Pa]", pmean / steps, "{:7.0f}"),
            ("least p, 3 dp [Pa]", pmin / steps, "{:7.0f}"), ("gap of nearest 5 [dp]", gap / steps, "{:7.2f}")]
    rows += [(f"shear across {y:g} dp [N/m]", lines[n] / steps, "{:7.3f}") for n, y in enumerate(LINES)]
    rows += [("particles within 6 dp", count / steps, "{:7.0f}"), ("nearest neighbour [dp]", nn_mean / steps, "{:7.2f}"),
             ("  its tenth percentile", nn_p10 / steps, "{:7.2f}")]
    for name, vals, fmt in rows:
        print(f"  {name:24s}" + " ".join(fmt.format(v) for v in vals))


if __name__ == "__main__":
    run = sys.argv[1]
    t0, t1 = (float(sys.argv[2]), float(sys.argv[3])) if len(sys.argv) > 3 else (2.0, 3.0)
    analyse(run, t0, t1)
