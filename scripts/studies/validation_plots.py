"""Plots spate's validation runs against experiment and theory (called by scripts/studies/validation-report)."""
import csv
import math
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

work, data, images = (Path(a) for a in sys.argv[1:4])
sys.path.insert(0, str(Path(__file__).parent))
import impact_metrics as im  # noqa: E402
from impact_plot import impact_figure  # noqa: E402


def probe(path, column):
    """Time [s] and one column of a probe CSV; columns are named without their unit ("pressure" for
    "pressure[Pa]")."""
    with open(path) as f:
        rows = [{k.split("[")[0]: v for k, v in r.items()} for r in csv.DictReader(f)]
    return [float(r["time"]) for r in rows], [float(r[column]) for r in rows]


def experiment(name):
    pts = []
    for line in open(data / name):
        if line.startswith("#") or line.startswith("T"):
            continue
        t, z = line.strip().split(",")
        pts.append((float(t), float(z)))
    return pts


# Dam break surge front: Z = front / a against T = t sqrt(2 g / a).
a, g = 0.0572, 9.81
t, x = probe(work / "dam_break_2d/probes/front.csv", "front")
T = [ti * math.sqrt(2 * g / a) for ti in t]
Z = [xi / a for xi in x]
fig, ax = plt.subplots(figsize=(6, 4))
ax.plot(T, Z, "k-", label="spate, dp = a/28.6")
for name, style, label in [("martin_moyce_1952_a2.25in.csv", "o", "Martin & Moyce 1952, a = 2.25 in"),
                           ("martin_moyce_1952_a1.125in.csv", "s", "Martin & Moyce 1952, a = 1.125 in"),
                           ("koshizuka_oka_1996_front.csv", "^", "Koshizuka & Oka 1996")]:
    pts = experiment(name)
    ax.plot([p[0] for p in pts], [p[1] for p in pts], style, mfc="none", label=label)
ax.set_xlim(0, 3.5)
ax.set_ylim(1, 5)
ax.set_xlabel("T = t sqrt(2g/a)")
ax.set_ylabel("Z = front / a")
ax.legend()
ax.grid(alpha=0.3)
fig.tight_layout()
fig.savefig(images / "validation_dam_break_front.png", dpi=110)
print("surge front (error against Martin & Moyce a = 2.25 in):")
for Te, Ze in experiment("martin_moyce_1952_a2.25in.csv"):
    if Te > 3.0:
        break
    k = min(range(len(T)), key=lambda i: abs(T[i] - Te))
    print(f"  T = {Te:.2f}: experiment {Ze:.3f}, spate {Z[k]:.3f}, error {100 * (Z[k] - Ze) / Ze:+.1f}%")

# Hydrostatic pressure against rho g d.
fig, ax = plt.subplots(figsize=(6, 4))
for name, depth in [("p_bottom", 0.45), ("p_middle", 0.25), ("p_upper", 0.1)]:
    t, p = probe(work / f"hydrostatic_2d/probes/{name}.csv", "pressure")
    ax.plot(t, [pi / (1000 * g * depth) for pi in p], label=f"depth {depth} m")
    late = [pi for ti, pi in zip(t, p) if ti > 0.7]
    print(f"hydrostatic {name}: mean over t > 0.7 s {sum(late) / len(late):.1f} Pa, rho g d = {1000 * g * depth:.1f} Pa, "
          f"error {100 * (sum(late) / len(late) / (1000 * g * depth) - 1):+.2f}%")
ax.axhline(1.0, color="k", lw=0.8)
ax.set_ylim(0.9, 1.1)
ax.set_xlabel("t [s]")
ax.set_ylabel("p / (rho g d)")
ax.legend()
ax.grid(alpha=0.3)
fig.tight_layout()
fig.savefig(images / "validation_hydrostatic.png", dpi=110)

# Poiseuille: centreline against the transient series solution (Morris et al. 1997).
F, nu, L = 2e-4, 1e-6, 1e-3
t, u = probe(work / "poiseuille_2d/probes/centreline.csv", "vx")


def series(time, y):
    s = F / (2 * nu) * y * (L - y)
    for n in range(200):
        k = 2 * n + 1
        s -= 4 * F * L * L / (nu * math.pi ** 3 * k ** 3) * math.sin(math.pi * y * k / L) * math.exp(-(k * math.pi / L) ** 2 * nu * time)
    return s


fig, ax = plt.subplots(figsize=(6, 4))
ax.plot(t, [ui * 1e5 for ui in u], "k-", label="spate centreline")
ax.plot(t, [series(ti, L / 2) * 1e5 for ti in t], "r--", label="series solution")
ax.set_xlabel("t [s]")
ax.set_ylabel("u [1e-5 m/s]")
ax.legend()
ax.grid(alpha=0.3)
fig.tight_layout()
fig.savefig(images / "validation_poiseuille.png", dpi=110)
print(f"poiseuille: centreline at t = {t[-1]:.2f} s: {u[-1]:.4g} m/s, analytic {F * L * L / (8 * nu):.4g} m/s, "
      f"error {100 * (u[-1] / (F * L * L / (8 * nu)) - 1):+.2f}%")

# Two fluids at rest (oil over water): pressures against the exact hydrostatic values, the water's
# surface under the oil and the oil's centroid.
exact = {"p_oil": 800 * g * 0.1, "p_water": 800 * g * 0.2 + 1000 * g * 0.2}
fig, (ax, ax2) = plt.subplots(1, 2, figsize=(10, 4))
for name, p_exact in exact.items():
    t, p = probe(work / f"two_layer_hydrostatic_2d/probes/{name}.csv", "pressure")
    ax.plot(t, [pi / p_exact for pi in p], label=f"{name} (exact {p_exact:.1f} Pa)")
    late = [pi for ti, pi in zip(t, p) if 0.5 <= ti <= 1.0]
    print(f"two layers {name}: mean over 0.5 s <= t <= 1 s {sum(late) / len(late):.1f} Pa, exact {p_exact:.1f} Pa, "
          f"error {100 * (sum(late) / len(late) / p_exact - 1):+.2f}%")
ax.axhline(1.0, color="k", lw=0.8)
ax.axhspan(0.99, 1.01, color="g", alpha=0.1)
ax.set_ylim(0.95, 1.05)
ax.set_xlabel("t [s]")
ax.set_ylabel("p / p_exact")
ax.legend()
ax.grid(alpha=0.3)
t, h = probe(work / "two_layer_hydrostatic_2d/probes/interface.csv", "height")
ax2.plot(t, h, label="water surface under the oil (height gauge, phase water)")
t, yc = probe(work / "two_layer_hydrostatic_2d/probes/oil_centroid.csv", "y")
ax2.plot(t, yc, label="oil centroid y")
ax2.axhline(0.3, color="k", lw=0.6, ls=":")
ax2.axhline(0.4, color="k", lw=0.6, ls=":")
ax2.set_ylim(0.28, 0.42)
ax2.set_xlabel("t [s]")
ax2.set_ylabel("y [m]")
ax2.legend(fontsize=8)
ax2.grid(alpha=0.3)
fig.tight_layout()
fig.savefig(images / "validation_two_layer.png", dpi=110)

# Impact pressures against Lobovsky et al. (2014) and Buchner (2002): each scheme's sensor (through
# its window, as the case's sensors average) and the experiment through the same window
# (docs/studies/impact-pressures.md, "Impact pressures"). Runs: <work>/<case>_<scheme> for each scheme present.
SCHEMES = [("default", "default (delta-SPH Fourtakas, central)"),
           ("riemann", "Riemann flux + diffusion"),
           ("riemann_notension", "Riemann + no tension")]


for case in ("dam_break_lobovsky", "dam_break_buchner_2d"):  # the cases scripts/studies/validation-report runs
    impact_figure(case, [(work / f"{case}_{k}", label) for k, label in SCHEMES], data, images / f"validation_{case}.png")
