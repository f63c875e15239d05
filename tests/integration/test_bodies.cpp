// Bodies the water moves (issue 32): the shipped floating box (cases/floating_box_2d.yaml) settles
// at the draft Archimedes gives and heaves with the period of its hydrostatic stiffness and mass
// plus added mass (docs/validation.md, "Floating box"); a dense one sinks and rests on the floor.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <string>
#include <vector>

#include "case/motion.hpp"
#include "run_helpers.hpp"
#include "wave_theory.hpp"

namespace spate {
namespace {

// The time and value of the extreme (sign +1: maximum, -1: minimum) of a probe column in [a, b],
// refined by a parabola through the 7 samples around it.
std::pair<double, double> extreme(const std::vector<std::pair<double, double>>& v, double a, double b, int sign) {
  std::size_t best = 0;
  bool found = false;
  for (std::size_t k = 3; k + 3 < v.size(); ++k)
    if (v[k].first >= a && v[k].first <= b && (!found || sign * v[k].second > sign * v[best].second)) best = k, found = true;
  if (!found) return {NAN, NAN};
  // Least-squares parabola y = c0 + c1 s + c2 s^2 in s = t - t_best.
  double S[5] = {0, 0, 0, 0, 0}, R[3] = {0, 0, 0};
  for (std::size_t k = best - 3; k <= best + 3; ++k) {
    const double s = v[k].first - v[best].first, y = v[k].second;
    double p = 1.0;
    for (int e = 0; e < 5; ++e) S[e] += p, p *= s;
    R[0] += y, R[1] += y * s, R[2] += y * s * s;
  }
  // Normal equations by Cramer's rule.
  const double M[3][3] = {{S[0], S[1], S[2]}, {S[1], S[2], S[3]}, {S[2], S[3], S[4]}};
  auto det = [](const double A[3][3]) {
    return A[0][0] * (A[1][1] * A[2][2] - A[1][2] * A[2][1]) - A[0][1] * (A[1][0] * A[2][2] - A[1][2] * A[2][0]) +
           A[0][2] * (A[1][0] * A[2][1] - A[1][1] * A[2][0]);
  };
  double c[3];
  for (int j = 0; j < 3; ++j) {
    double A[3][3];
    for (int r = 0; r < 3; ++r)
      for (int q = 0; q < 3; ++q) A[r][q] = q == j ? R[r] : M[r][q];
    c[j] = det(A) / det(M);
  }
  const double s = -c[1] / (2.0 * c[2]);
  return {v[best].first + s, c[0] + c[1] * s + c[2] * s * s};
}

// The body probe `box` of a run of the case (its columns x, y, angle from the second), on 2 threads.
struct BoxRecord {
  std::vector<std::pair<double, double>> x, y, angle;
  std::filesystem::path csv;
};
BoxRecord run_box(const Case& c, const std::string& scratch) {
  const auto out = test::scratch(scratch);
  RunOptions o;
  o.threads = 2;
  const RunResult r = test::run_case(c, out, o);
  EXPECT_EQ(r.exit_code, 0) << r.message;
  BoxRecord b;
  b.csv = out / "probes" / "box.csv";
  b.x = test::read_probe(b.csv, 2), b.y = test::read_probe(b.csv, 3), b.angle = test::read_probe(b.csv, 4);
  EXPECT_GT(b.y.size(), 100u);
  return b;
}

// The box (0.2 m x 0.1 m, density 500) is released at a draft of 0.04 m, 1 cm above its equilibrium,
// free in x, y and its rotation. Archimedes: draft d = rho_b H / rho_w = 0.05 m, where the still
// water then stands at h_s = (A_water + B d) / L = 0.301 m (the water's area conserved), so that the
// box's centre rests at h_s - d + H/2. Its mean centre over 0.8 to 1.5 s (after the first period,
// before the tank's slow seiche builds) gives the draft within 2% (measured -0.18% with the viscous
// load, +0.47% with the pressure alone; at dp = 0.02 it is -2.3%, hence dp = 0.01). The heave period, release (a maximum) to the next maximum, against
// T = 2 pi sqrt((m + a33) / (rho g B)) with the added mass a33 = rho pi B^2 / 8 of a flat plate on
// the surface (Korotkin 2009, "Added masses of ship structures", 5.31; the high-frequency limit),
// 0.719 s: within 10% (measured 0.721 s, +0.2%; -4.9% with the pressure alone). The box stays
// upright (within 2 degrees) and in place within 5 mm in this symmetric setting: rounding excites
// the tank's first (antisymmetric) seiche, whose flow under the box drags it by a few millimetres
// once the load has its viscous part (2.7 mm by 1.5 s; 0.7 mm with the pressure alone).
TEST(FloatingBodies, ABoxSettlesAtArchimedesDraftWithItsHeavePeriod) {
  if (!body_support()) GTEST_SKIP() << "built without Simbody";
  const Case c = load_case(test::case_path("floating_box_2d.yaml"),
                           {"time.end=1.5", "output.interval=0",
                            "probes=[{name: box, type: body, solid: box}, {name: level, type: height, position: [0.3]}, "
                            "{name: under, type: pressure, position: [1.0, 0.255], follow: box}]"});
  const BoxRecord box = run_box(c, "floating-box");
  const auto& csv = box.csv;
  const auto &y = box.y, &angle = box.angle, &x = box.x;
  ASSERT_GT(y.size(), 100u);
  const double rho = c.fluids[0].density, g = std::fabs(c.gravity[1]), B = 0.2, H = 0.1;
  const double m = c.bodies[0].mass, draft = m / (rho * B);
  EXPECT_NEAR(draft, 0.05, 1e-12);
  const double L = c.tank_size[0], water = L * 0.3 - B * (0.3 - 0.26);
  const double still = (water + B * draft) / L;
  const double mean = test::mean_after(csv, 3, 0.8);
  const double measured = still - (mean - H / 2);
  std::printf("draft %.5f m (Archimedes %.5f m, %+.2f%%), still water at %.5f m\n", measured, draft, 100 * (measured - draft) / draft, still);
  EXPECT_NEAR(measured, draft, 0.02 * draft);
  const auto low = extreme(y, 0.2, 0.5, -1), high = extreme(y, 0.5, 0.9, +1);
  const double a33 = rho * 3.14159265358979323846 * B * B / 8.0;
  const double period = 2 * 3.14159265358979323846 * std::sqrt((m + a33) / (rho * g * B));
  std::printf("heave: down to %.5f m at %.3f s, up to %.5f m at %.3f s: period %.3f s (theory %.3f s, %+.1f%%)\n", low.second,
              low.first, high.second, high.first, high.first, period, 100 * (high.first - period) / period);
  EXPECT_LT(low.second, still - draft + H / 2 - 0.002);  // it overshoots its equilibrium: an oscillation, not a creep
  EXPECT_NEAR(high.first, period, 0.1 * period);
  double tilt = 0.0, drift = 0.0;
  for (std::size_t k = 0; k < angle.size(); ++k) tilt = std::max(tilt, std::fabs(angle[k].second)), drift = std::max(drift, std::fabs(x[k].second - 1.0));
  EXPECT_LT(tilt, 2.0);
  EXPECT_LT(drift, 5e-3);
  // A pressure probe riding with the box, dp/2 under the middle of its bottom: at rest it reads
  // the box's weight over its width plus the water above it, m g / B + rho g dp/2, within 8%
  // (measured +4.2%; a probe left where it started, 0.9 cm higher than the box took it, would
  // read 16% less).
  const double under = test::mean_after(box.csv.parent_path() / "under.csv", 2, 0.8);
  const double expected = m * g / B + rho * g * 0.5 * c.dp;
  std::printf("under the box: %.1f Pa (m g / B + rho g dp/2 = %.1f Pa, %+.1f%%)\n", under, expected, 100 * (under - expected) / expected);
  EXPECT_NEAR(under, expected, 0.08 * expected);
}

// Contact with the tank (docs/physics.md, "Contact"): the same box four times as dense (2000 kg/m3)
// sinks through 0.26 m of water and comes to rest on the floor, level and in place, its centre half
// its height above the floor (within the contact spheres' dp/100 and their penetration): it never
// passes into the floor. At dp = 0.02 (the box's faces on that lattice too), 1.5 s.
TEST(FloatingBodies, ADenseBoxSinksAndRestsOnTheFloor) {
  if (!body_support()) GTEST_SKIP() << "built without Simbody";
  const Case c = load_case(test::case_path("floating_box_2d.yaml"),
                           {"dp=0.02", "time.end=1.5", "output.interval=0",
                            "solids=[{name: box, polygon: [[0.9, 0.26], [1.1, 0.26], [1.1, 0.36], [0.9, 0.36]], motion: floating, density: 2000}]"});
  ASSERT_TRUE(c.bodies[0].contact.on);
  const BoxRecord box = run_box(c, "sinking-box");
  const auto& csv = box.csv;
  const auto &y = box.y, &angle = box.angle, &x = box.x;
  ASSERT_GT(y.size(), 100u);
  double lowest = 1.0;
  for (const auto& [t, v] : y) lowest = std::min(lowest, v);
  const double rest = test::mean_after(csv, 3, 1.2);
  std::printf("lowest centre %.5f m, at rest %.5f m (on the floor: 0.05 m)\n", lowest, rest);
  EXPECT_GT(lowest, 0.05 - 0.1 * c.dp);
  EXPECT_NEAR(rest, 0.05, 0.02 * c.dp);
  EXPECT_LT(std::fabs(angle.back().second), 0.5);
  EXPECT_NEAR(x.back().second, 1.0, 0.1 * c.dp);
}

// cases/hinged_flap_2d.yaml: a bottom-hinged flap (0.06 x 0.56 m, density 500, a 300 N m/rad spring)
// across the piston flume's regular waves (T = 1.2 s, 0.4 m deep). Its rotation per metre of
// incident amplitude against linear potential-flow theory, 2.910 rad/m
// (scripts/studies/hinged_flap_theory.py cases/hinged_flap_2d.yaml: the flap wave maker's radiation
// on both faces, the excitation of a flap held still; docs/validation.md, "Hinged flap"), within
// 15% (issue 32's level for bodies in waves), and the wave it reflects, 0.589 of the incident,
// within 0.1. The incident and reflected waves come from the gauge pair ahead1/ahead2 (Goda &
// Suzuki's two-gauge separation), read over the flap's window: from the steady train's arrival at
// the flap until 11.6 s (3.3 periods; the flap's reflection comes back off the piston at 13.5 s,
// windows from the group velocity). Measured -3.3% and 0.521 (the study, to 13.5 s with the
// incident wave from the flume without the flap: -2.1%). The angle column counts
// counter-clockwise, so the flap leaning downstream reads negative.
TEST(FloatingBodies, AHingedFlapInWavesRocksAsLinearTheorySays) {
  if (!body_support()) GTEST_SKIP() << "built without Simbody";
  const Case c = load_case(test::case_path("hinged_flap_2d.yaml"), {"time.end=11.6", "output.interval=0"});
  // The theory's number is for these: a changed case needs scripts/studies/hinged_flap_theory.py again.
  const BodySpec& flap = c.bodies.at(0);
  ASSERT_TRUE(flap.hinge.on);
  ASSERT_DOUBLE_EQ(flap.hinge.stiffness, 300.0);
  ASSERT_NEAR(flap.mass, 500 * 0.06 * 0.56, 1e-9);
  const MotionSpec& piston = c.motions[0];
  const double omega = piston.omega, T = 2 * std::numbers::pi / omega, depth = c.fluid_blocks[0].max[1];
  ASSERT_NEAR(T, 1.2, 1e-9);
  ASSERT_NEAR(depth, 0.4, 1e-12);
  constexpr double kTheory = 2.910;      // |Theta| / A [rad/m]
  constexpr double kReflection = 0.589;  // the reflected wave over the incident
  constexpr double kEnd = 11.6;          // the steady window's first 3.3 periods (the study reads to 13.5 s): CI's time
  const auto out = test::scratch("hinged-flap");
  RunOptions o;
  o.threads = 2;
  o.until = kEnd;
  const RunResult r = test::run_case(c, out, o);
  ASSERT_EQ(r.exit_code, 0) << r.message;
  const double k = test::wavenumber(omega, depth), kd = k * depth;
  const double cg = 0.5 * omega / k * (1 + 2 * kd / std::sinh(2 * kd));
  const double x_flap = 5.03, ramp = 2 * T;
  const double t0 = ramp + x_flap / cg + T / 2, t1 = std::min(3 * x_flap / cg, kEnd);
  const std::vector<double> harmonics{omega, 2 * omega};
  auto phasor = [&](const char* probe, int column) {
    return test::harmonic_phasors(test::read_probe(out / "probes" / (std::string(probe) + ".csv"), column), t0, t1, harmonics)[0];
  };
  const auto [incident, reflected] = test::incident_and_reflected(phasor("ahead1", 2), phasor("ahead2", 2), 3.5, 3.8, k);
  const double A = std::abs(incident), theta = std::abs(phasor("flap", 4)) * std::numbers::pi / 180;
  const double R = std::abs(reflected) / A;
  std::printf("hinged flap: incident amplitude %.4f m, rotation %.4f rad: %.3f rad/m (linear theory %.3f, %+.1f%%); reflection %.3f (theory %.3f)\n",
              A, theta, theta / A, kTheory, 100 * (theta / A / kTheory - 1), R, kReflection);
  RecordProperty("rao_error", std::to_string(theta / A / kTheory - 1));
  EXPECT_NEAR(A, 0.025, 0.1 * 0.025);  // Biesel's H / 2 (WaveFlume.BieselWaveHeightAndPeriodAtG1)
  EXPECT_NEAR(theta / A, kTheory, 0.15 * kTheory);
  EXPECT_NEAR(R, kReflection, 0.1);
}

}  // namespace
}  // namespace spate
