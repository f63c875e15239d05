#!/usr/bin/env python3
"""Linear potential-flow response of a bottom-hinged flap in regular waves, 2D (issue 32's reference
for cases/hinged_flap_2d.yaml).

A thin flap spans the whole depth h of a channel with water on both sides, hinged on the floor,
turning by theta(t) = Re(Theta e^{-i w t}) (positive: its top moves downstream, +x). Linear theory,
a flap held still and a flap moving in still water, superposed:

* Radiation (the flap wave maker's problem, Havelock 1929; Dean & Dalrymple 1991, ch. 6): on the lee
  side the potential is a_0 cosh k0(z+h) e^{i k0 x} + sum_n a_n cos kn(z+h) e^{-kn x}, with
  w^2 = g k0 tanh k0 h and w^2 = -g kn tan kn h; the flap's velocity -i w Theta (z + h) projected on
  these depth functions gives the a_n. The weather side's potential is the mirror with the opposite
  sign, so both faces push alike: the torque about the hinge is 2 * (-i w rho) sum a_n I_n with
  I_n = integral of (z + h) f_n(z) over the depth, which is (w^2 I_a + i w B) Theta: the added
  inertia I_a and the radiation damping B.
* Excitation: a flap held still across the channel reflects the incident wave whole (a vertical
  wall over the full depth: no evanescent modes), so the weather face carries twice the incident
  wave's dynamic pressure, 2 rho g A cosh k0(z+h) / cosh k0 h, the lee face none: the torque is
  2 rho g A I_0 / cosh k0 h, in phase with the incident crest at the flap.
* The flap: (-w^2 (I_f + I_a) - i w (B + c) + C + k) Theta = M, with I_f its inertia about the hinge,
  c and k the hinge's damper and spring, and C = rho g b h^2 / 2 - m g z_G the hydrostatic
  stiffness of a flap of thickness b (its buoyancy's moment less its weight's).

The flap of the case is 3 dp thick (0.06 m, 15% of the depth; the thin-flap theory treats both faces
as one plane). Usage: hinged_flap_theory.py [CASE.yaml]: prints |Theta| / A and the phase lag for the
case's flap and waves.
"""
import cmath
import math
import sys

G, RHO = 9.81, 1000.0


def _root(f, lo, hi):
    flo = f(lo)
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        fm = f(mid)
        if (fm < 0) == (flo < 0):
            lo, flo = mid, fm
        else:
            hi = mid
    return 0.5 * (lo + hi)


def wavenumbers(omega, h, modes=400):
    """k0 of the propagating mode and the first `modes` evanescent kn."""
    k0 = _root(lambda k: G * k * math.tanh(k * h) - omega**2, 1e-9, 100.0 / h)
    kn = [_root(lambda q: omega**2 + G * q * math.tan(q * h), (j - 0.5) * math.pi / h + 1e-12, j * math.pi / h - 1e-12)
          for j in range(1, modes + 1)]
    return k0, kn


def radiation(omega, h, modes=400):
    """(I_a, B): added inertia [kg m^2 per m] and radiation damping [N m s per m] of the flap, both faces."""
    k0, kn = wavenumbers(omega, h, modes)
    N0 = (math.sinh(2 * k0 * h) / (2 * k0) + h) / 2
    I0 = h * math.sinh(k0 * h) / k0 - (math.cosh(k0 * h) - 1) / k0**2
    s = (-1j * omega * I0) / (1j * k0 * N0) * I0
    for q in kn:
        Nn = (math.sin(2 * q * h) / (2 * q) + h) / 2
        In = h * math.sin(q * h) / q + (math.cos(q * h) - 1) / q**2
        s += (-1j * omega * In) / (-q * Nn) * In
    torque = 2 * (-1j * omega * RHO) * s
    return torque.real / omega**2, torque.imag / omega


def excitation(omega, h):
    """Torque [N m per m] per metre of incident amplitude on the flap held still."""
    k0, _ = wavenumbers(omega, h, 0)
    I0 = h * math.sinh(k0 * h) / k0 - (math.cosh(k0 * h) - 1) / k0**2
    return 2 * RHO * G * I0 / math.cosh(k0 * h)


def reflection_transmission(period, h, theta):
    """(R, T): the reflected and transmitted waves over the incident, for the flap's Theta / A. The flap
    held still reflects the wave whole (R = 1); moving, it radiates eta_r Theta downstream and the
    mirror, -eta_r Theta, upstream (eta = (i w / g) phi at the surface). Without damping in the hinge
    |R|^2 + |T|^2 = 1 (a check of the signs)."""
    omega = 2 * math.pi / period
    k0, _ = wavenumbers(omega, h, 0)
    N0 = (math.sinh(2 * k0 * h) / (2 * k0) + h) / 2
    I0 = h * math.sinh(k0 * h) / k0 - (math.cosh(k0 * h) - 1) / k0**2
    eta = (1j * omega / G) * (-1j * omega * I0) / (1j * k0 * N0) * math.cosh(k0 * h)
    return 1 - eta * theta, eta * theta


def response(period, h, inertia, hydrostatic, stiffness=0.0, damping=0.0):
    """Complex Theta / A [rad/m]: theta = |Theta| A cos(w t - phase) for an incident crest eta = A cos(w t) at the flap."""
    omega = 2 * math.pi / period
    Ia, B = radiation(omega, h)
    impedance = -omega**2 * (inertia + Ia) - 1j * omega * (B + damping) + hydrostatic + stiffness
    return excitation(omega, h) / impedance


def flap_of_case(path):
    """The case's flap (a rectangle hinged at its bottom's middle) and waves."""
    import yaml
    c = yaml.safe_load(open(path))
    h = c["fluid_blocks"][0]["max"][1]
    piston = next(s for s in c["solids"] if s["name"] == "piston")
    flap = next(s for s in c["solids"] if s["name"] == "flap")
    xs = [p[0] for p in flap["polygon"]]
    ys = [p[1] for p in flap["polygon"]]
    b, L = max(xs) - min(xs), max(ys) - min(ys)
    m = flap["density"] * b * L
    inertia = m * (L**2 / 3 + b**2 / 12)
    hydrostatic = RHO * G * b * h**2 / 2 - m * G * L / 2
    hinge = flap["hinge"]
    return dict(period=piston["motion"]["period"], h=h, inertia=inertia, hydrostatic=hydrostatic,
                stiffness=hinge.get("stiffness", 0.0), damping=hinge.get("damping", 0.0), mass=m, x=0.5 * (min(xs) + max(xs)))


if __name__ == "__main__":
    f = flap_of_case(sys.argv[1] if len(sys.argv) > 1 else "cases/hinged_flap_2d.yaml")
    omega = 2 * math.pi / f["period"]
    Ia, B = radiation(omega, f["h"])
    r = response(f["period"], f["h"], f["inertia"], f["hydrostatic"], f["stiffness"], f["damping"])
    print(f"flap: mass {f['mass']:.2f} kg/m, inertia about the hinge {f['inertia']:.4f} kg m, hydrostatic stiffness "
          f"{f['hydrostatic']:.2f} N m/rad, spring {f['stiffness']} N m/rad")
    print(f"T = {f['period']} s, h = {f['h']} m: added inertia {Ia:.4f} kg m, radiation damping {B:.3f} N m s, "
          f"excitation {excitation(omega, f['h']):.1f} N m per m of amplitude")
    print(f"|Theta| / A = {abs(r):.4f} rad/m, lagging the incident crest by {math.degrees(cmath.phase(r)):.1f} degrees")
    R, T = reflection_transmission(f["period"], f["h"], r)
    print(f"reflection |R| = {abs(R):.4f}, transmission |T| = {abs(T):.4f} (|R|^2 + |T|^2 = {abs(R)**2 + abs(T)**2:.6f})")
