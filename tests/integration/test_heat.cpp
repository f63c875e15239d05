// Heat transfer against exact solutions (label `validation`; physics/heat_transfer.hpp): steady
// conduction through two materials (cases/conduction_2d.yaml), the decay of a sinusoidal
// temperature (cases/conduction_wave_2d.yaml), and bit-identical results for any split.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "run_helpers.hpp"
#include "io/checkpoint.hpp"
#include "sim/insitu.hpp"
#include "sim/steering.hpp"

namespace spate {
namespace {

// The final particles of a run, with the thermal fields (read while a heat run's fields are on).
ParticleStore final_particles(const RunResult& r) {
  const OptionalFields thermal(FieldGroups{kThermal});
  ParticleStore p(2);
  read_checkpoint(r.last_checkpoint, p);
  return p;
}

// A liner (k = 10) and a fluid at rest (k = 1), 0.05 m each, between faces at 310 and 290 K: the
// steady profile is piecewise linear, q = 20 / (0.05/10 + 0.05/1) = 363.6 W/m^2 through both, the
// interface at 308.18 K. Every particle within 1% of the 20 K difference (0.1% measured), the
// interface temperature (each side's straight-line fit extrapolated to it) within 1% too (0.1%),
// the flux through the cold face within 1% (0.01%).
TEST(Heat, ConductionThroughTwoMaterialsReachesTheExactProfile) {
  const Case c = load_case(test::case_path("conduction_2d.yaml"), {"output.interval=0"});
  const auto out = test::scratch("heat-slab");
  const RunResult r = test::run_case(c, out);
  ASSERT_EQ(r.exit_code, 0) << r.message;
  const ParticleStore p = final_particles(r);
  ASSERT_EQ(p.temperature.size(), p.size());
  const double q = 20.0 / (0.05 / 10 + 0.05 / 1), t_interface = 310.0 - q * 0.05 / 10;
  auto exact = [&](double x) { return x < 0.05 ? 310.0 - q * x / 10 : t_interface - q * (x - 0.05); };
  double worst = 0.0;
  // Least-squares lines T = a + b x on each side.
  double s[2][5] = {};
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double x = p.pos[0][i], y = p.pos[1][i], t = p.temperature[i];
    if (x <= 0 || x >= 0.1 || y <= 0 || y >= 0.05) continue;  // walls
    worst = std::max(worst, std::fabs(t - exact(x)));
    double* side = s[x < 0.05 ? 0 : 1];
    side[0] += 1, side[1] += x, side[2] += t, side[3] += x * x, side[4] += x * t;
  }
  std::printf("max |T - exact| = %.4f K\n", worst);
  EXPECT_LT(worst, 0.01 * 20.0);
  for (auto& side : s) {
    const double b = (side[0] * side[4] - side[1] * side[2]) / (side[0] * side[3] - side[1] * side[1]);
    const double a = (side[2] - b * side[1]) / side[0];
    std::printf("interface temperature from one side: %.4f K (exact %.4f)\n", a + b * 0.05, t_interface);
    EXPECT_NEAR(a + b * 0.05, t_interface, 0.01 * 20.0);
  }
  const auto cold = test::read_probe(out / "probes" / "q_cold.csv", 2);
  ASSERT_FALSE(cold.empty());
  std::printf("flux into the fluid through the cold face: %.2f W/m2 (exact %.2f)\n", cold.back().second, -q);
  EXPECT_NEAR(cold.back().second, -q, 0.01 * q);
}

// T = 300 + 10 sin(2 pi x / 0.1) in a fluid at rest, periodic along x, adiabatic above and below:
// the amplitude decays as exp(-alpha k^2 t) with alpha = 1e-3 m^2/s. At one e-folding time the
// amplitude (the probe at the crest) within 2% of exact (0.3% measured), the trough the mirror.
TEST(Heat, SinusoidDecaysAtTheDiffusionRate) {
  const Case c = load_case(test::case_path("conduction_wave_2d.yaml"));
  const auto out = test::scratch("heat-wave");
  const RunResult r = test::run_case(c, out);
  ASSERT_EQ(r.exit_code, 0) << r.message;
  const auto crest = test::read_probe(out / "probes" / "t_crest.csv", 2);
  const auto trough = test::read_probe(out / "probes" / "t_trough.csv", 2);
  ASSERT_GT(crest.size(), 20u);
  const double rate = 1e-3 * std::pow(2 * M_PI / 0.1, 2), e_fold = 1.0 / rate;
  std::size_t k = 0;
  while (k + 1 < crest.size() && crest[k].first < e_fold) ++k;
  const double ratio = (crest[k].second - 300.0) / (crest[0].second - 300.0);
  const double expected = std::exp(-rate * (crest[k].first - crest[0].first));
  std::printf("amplitude at t = %.4f s: %.4f of the start (exact %.4f)\n", crest[k].first, ratio, expected);
  EXPECT_NEAR(ratio, expected, 0.02 * expected);
  EXPECT_NEAR(crest[k].second - 300.0, 300.0 - trough[k].second, 1e-3);
}

// The mean of probe column `col` over [from, to] seconds.
double mean_over(const std::filesystem::path& csv, int col, double from, double to) {
  double sum = 0;
  int n = 0;
  for (auto [t, v] : test::read_probe(csv, col))
    if (t >= from && t <= to) sum += v, ++n;
  return n ? sum / n : NAN;
}

// The largest speed of the fluid particles within dp/2 of a mid-line (axis `across` at L/2), along
// `component`, in units of alpha / L, and where along the line it is (in units of L).
std::pair<double, double> mid_line_maximum(const SlabView& p, int across, int component, double L, double dp, double alpha) {
  const std::uint8_t* kind = p.array("kind")->values<std::uint8_t>();
  const float* velocity = p.array("velocity")->values<float>(component);
  double best = 0, at = 0;
  for (std::size_t i = 0; i < p.owned; ++i) {
    if (kind[i] != 0 || std::fabs(p.pos[across][i] - 0.5 * L) > 0.5 * dp) continue;
    if (std::fabs(velocity[i]) > best) best = std::fabs(velocity[i]), at = p.pos[1 - across][i];
  }
  return {best * L / alpha, at / L};
}

// The mid-lines' largest velocities (mid_line_maximum) once a second from `from` on, averaged: one
// particle's speed at one instant wanders by 2-4% from second to second in the settled flow (the
// particles that happen to lie on the line, and their noise), as much as a change in the last bit
// of a sum moves it, so the mean over the seconds is what is compared, as Nu is.
class MidLineSampler : public InSituSink {
 public:
  MidLineSampler(double from, double L, double dp, double alpha) : next_(from), L_(L), dp_(dp), alpha_(alpha) {}
  bool wants(std::int64_t, double time) override { return time >= next_; }
  void execute(std::int64_t, double time, const std::vector<SlabView>& slabs) override {
    while (next_ <= time) next_ += 1.0;
    ASSERT_EQ(slabs.size(), 1u);
    u_.push_back(mid_line_maximum(slabs[0], 0, 0, L_, dp_, alpha_));
    v_.push_back(mid_line_maximum(slabs[0], 1, 1, L_, dp_, alpha_));
  }
  // The mean speed and the mean place along the line (by symmetry, the place folded into the
  // half that the benchmark quotes: above the centre for u, left of it for v).
  std::pair<double, double> mean_u() const { return mean(u_, true); }
  std::pair<double, double> mean_v() const { return mean(v_, false); }
  std::size_t samples() const { return u_.size(); }

 private:
  static std::pair<double, double> mean(const std::vector<std::pair<double, double>>& s, bool upper) {
    double speed = 0, at = 0;
    for (auto [value, place] : s) speed += value, at += upper == (place > 0.5) ? place : 1.0 - place;
    return {speed / s.size(), at / s.size()};
  }
  double next_, L_, dp_, alpha_;
  std::vector<std::pair<double, double>> u_, v_;
};

// The differentially heated cavity of de Vahl Davis (1983), cases/heated_cavity_2d.yaml at the
// shipped 40 particles across: the hot wall's mean Nusselt number (the probe nu_hot, averaged
// over the last 10 s of the run, once the flow has settled) within 3% of the benchmark at Ra = 1e4
// (2.243; 2.189 measured) and at Ra = 1e3 (1.118; 1.097 measured), the cold wall's the same within
// 3% (the heat that enters leaves), and the largest velocities on the mid-lines over the same 10 s
// (MidLineSampler; u 16.178 alpha/L at y = 0.823 L, v 19.617 at x = 0.119 L for Ra = 1e4; 3.649,
// 3.697 for Ra = 1e3) within 6% at Ra = 1e4 (5.1% and 3.7% low measured) and 12% at Ra = 1e3
// (7.7% and 8.4% low: the slow flow is too weak, an open
// problem of docs/studies/heated-cavity.md, which also has the slow rise of Nu with time and the
// other resolutions).
TEST(Heat, HeatedCavityNusseltAgainstDeVahlDavis) {
  struct Point {
    const char* expansion;
    double end, nu, u, v, velocity_tolerance;
  };
  const double L = 0.05, alpha = 0.0257 / (1.2 * 1005);
  for (const Point& ra : {Point{"2.6295e-3", 40.0, 2.243, 16.178, 19.617, 0.06}, Point{"2.6295e-4", 60.0, 1.118, 3.649, 3.697, 0.12}}) {
    const Case c = load_case(test::case_path("heated_cavity_2d.yaml"),
                             {"output.interval=0", std::string("fluid.thermal.expansion=") + ra.expansion, "time.end=" + std::to_string(ra.end)});
    const auto out = test::scratch(std::string("heat-cavity-") + ra.expansion);
    RunOptions o;
    o.threads = 2;
    MidLineSampler mid_lines(ra.end - 10, L, c.dp, alpha);
    o.insitu = &mid_lines;
    const RunResult r = test::run_case(c, out, o);
    ASSERT_EQ(r.exit_code, 0) << r.message;
    ASSERT_GE(mid_lines.samples(), 10u);
    const double hot = mean_over(out / "probes" / "nu_hot.csv", 3, ra.end - 10, ra.end);
    const double cold = mean_over(out / "probes" / "nu_cold.csv", 3, ra.end - 10, ra.end);
    const auto [u, y] = mid_lines.mean_u();
    const auto [v, x] = mid_lines.mean_v();
    std::printf("beta %s: Nu hot %.4f cold %.4f (benchmark %.3f); over the last 10 s u_max %.3f at y = %.3f L, v_max %.3f at x = %.3f L\n",
                ra.expansion, hot, cold, ra.nu, u, y, v, x);
    EXPECT_NEAR(hot, ra.nu, 0.03 * ra.nu);
    EXPECT_NEAR(cold, ra.nu, 0.03 * ra.nu);
    EXPECT_NEAR(u, ra.u, ra.velocity_tolerance * ra.u);
    EXPECT_NEAR(v, ra.v, ra.velocity_tolerance * ra.v);
  }
}

// Steering a face (docs/live.md, `face_temperature`, `face_heat_flux`), replayed from a log as a
// live change would be: the slab's cold face (x+, face 1) steered from 290 to 300 K from the first
// step halves the flux through it (181.8 W/m^2 at the steady state, within 1%: 0.1% measured), and
// the same face switched to a heat flux of -181.8 W/m^2 reaches the same steady profile (the
// fluid's middle within 0.1 K of 304.32 K; measured 0.01). The steered run is the same on one device
// and on three slabs; a face the 2D tank does not have is rejected and the run goes on unsteered.
TEST(Heat, SteeringAFaceTemperatureOrFlux) {
  const double q = 10.0 / (0.05 / 10 + 0.05 / 1), t_mid = 310.0 - q * 0.005 - q * (0.07625 - 0.05);
  auto steered = [&](const std::string& log, const std::string& tag, double end, int devices = 1) {
    const Case c = load_case(test::case_path("conduction_2d.yaml"), {"output.interval=0", "time.end=" + std::to_string(end)});
    SteeringReplay replay(parse_log(log, "test log"));
    RunOptions o;
    o.steering = &replay;
    o.devices = devices;
    const RunResult r = test::run_case(c, test::scratch("heat-steer-" + tag), o);
    EXPECT_EQ(r.exit_code, 0) << r.message;
    return r;
  };
  auto last = [](const RunResult& r, const std::string& probe) {
    const auto v = test::read_probe(r.last_checkpoint.parent_path().parent_path() / "probes" / (probe + ".csv"), 2);
    return v.empty() ? NAN : v.back().second;
  };
  const RunResult fixed = steered("0 0 face_temperature 1 300\n", "fixed", 2.5);
  EXPECT_EQ(fixed.steering_accepted, 1);
  std::printf("cold face steered to 300 K: flux %.2f W/m2 (exact %.2f)\n", last(fixed, "q_cold"), -q);
  EXPECT_NEAR(last(fixed, "q_cold"), -q, 0.01 * q);
  const RunResult flux = steered("0 0 face_heat_flux 1 " + std::to_string(-q) + "\n", "flux", 7.0);
  std::printf("cold face steered to a flux of %.2f W/m2: fluid middle at %.3f K (exact %.3f), flux %.2f\n", -q,
              last(flux, "t_mid_fluid"), t_mid, last(flux, "q_cold"));
  EXPECT_NEAR(last(flux, "t_mid_fluid"), t_mid, 0.1);
  EXPECT_NEAR(last(flux, "q_cold"), -q, 0.01 * q);
  const RunResult split = steered("0 0 face_temperature 1 300\n", "fixed-3", 0.2, 3);
  const RunResult one = steered("0 0 face_temperature 1 300\n", "fixed-1", 0.2, 1);
  const OptionalFields thermal(FieldGroups{kThermal});
  std::string why;
  EXPECT_TRUE(test::identical_checkpoints(one.last_checkpoint, split.last_checkpoint, &why)) << why;
  const RunResult rejected = steered("0 0 face_temperature 4 300\n", "rejected", 0.2);
  EXPECT_EQ(rejected.steering_rejected, 1);
  EXPECT_EQ(rejected.steering_accepted, 0);
}

// A temperature-dependent viscosity (a fluid's thermal.viscosity table) against an exact solution:
// plane Poiseuille flow between a floor at 290 K and a lid at 310 K (cases/poiseuille_thermal_2d.yaml),
// where conduction settles to a linear temperature and mu(T), 2 -> 1 -> 0.5 mPa s, makes the profile
// lean towards the thin, hot side. mu du/dy = rho F (y* - y) with u = 0 on both walls gives
// y* = int y / mu / int 1 / mu and u(y) = int_0^y rho F (y* - s) / mu(s) ds (by quadrature here).
// The velocities at a quarter, half and three quarters of the width within 3% (the constant-
// viscosity Poiseuille test's tolerance; measured +1.6, +1.2, +0.7%) and the lean, u(3L/4) / u(L/4) =
// 1.59 (1 with a constant viscosity), within 3% (0.8%).
TEST(Heat, ViscosityFollowsTheTemperatureInAPoiseuilleChannel) {
  const Case c = load_case(test::case_path("poiseuille_thermal_2d.yaml"), {"output.interval=0"});
  const auto out = test::scratch("heat-poiseuille");
  const RunResult r = test::run_case(c, out);
  ASSERT_EQ(r.exit_code, 0) << r.message;
  const double L = c.tank_size[1], F = c.body_force[0], rho = c.fluids[0].density;
  const auto& table = c.fluids[0].thermal.viscosity;
  auto mu = [&](double y) {
    const double T = 290.0 + 20.0 * y / L;
    for (std::size_t k = 1; k < table.size(); ++k)
      if (T <= table[k][0]) return table[k - 1][1] + (T - table[k - 1][0]) / (table[k][0] - table[k - 1][0]) * (table[k][1] - table[k - 1][1]);
    return table.back()[1];
  };
  const int n = 20000;
  const double dy = L / n;
  double a = 0.0, b = 0.0;  // int y / mu, int 1 / mu (midpoint rule)
  for (int k = 0; k < n; ++k) {
    const double y = (k + 0.5) * dy;
    a += y / mu(y) * dy, b += dy / mu(y);
  }
  const double y_star = a / b;
  auto exact = [&](double y) {
    double u = 0.0;
    for (int k = 0; k < n && (k + 0.5) * dy < y; ++k) u += rho * F * (y_star - (k + 0.5) * dy) / mu((k + 0.5) * dy) * dy;
    return u;
  };
  double u[3];
  const char* names[3] = {"quarter", "centreline", "three_quarter"};
  for (int q = 0; q < 3; ++q) {
    const auto v = test::read_probe(out / "probes" / (std::string(names[q]) + ".csv"), 2);
    ASSERT_FALSE(v.empty());
    u[q] = v.back().second;
    const double e = exact((q + 1) * 0.25 * L);
    std::printf("u(%g L) = %.4e m/s, exact %.4e (%+.1f%%)\n", (q + 1) * 0.25, u[q], e, 100 * (u[q] / e - 1));
    EXPECT_NEAR(u[q], e, 0.03 * e) << names[q];
  }
  const double lean = exact(0.75 * L) / exact(0.25 * L);
  std::printf("u(3L/4) / u(L/4) = %.3f, exact %.3f\n", u[2] / u[0], lean);
  EXPECT_NEAR(u[2] / u[0], lean, 0.03 * lean);
  const auto t = test::read_probe(out / "probes" / "centre_temperature.csv", 2);
  ASSERT_FALSE(t.empty());
  EXPECT_NEAR(t.back().second, 300.0, 0.05);
}

// Heat transfer keeps results independent of the split: the slab on one device and on three.
TEST(Heat, BitIdenticalForAnySplit) {
  Case c = load_case(test::case_path("conduction_2d.yaml"), {"output.interval=0"});
  c.balance_every = 20;
  RunOptions o;
  o.steps = 150;
  const RunResult a = test::run_case(c, test::scratch("heat-split-1"), o);
  o.devices = 3;
  const RunResult b = test::run_case(c, test::scratch("heat-split-3"), o);
  ASSERT_EQ(a.exit_code, 0) << a.message;
  ASSERT_EQ(b.exit_code, 0) << b.message;
  const OptionalFields thermal(FieldGroups{kThermal});  // the thermal fields are compared too
  std::string why;
  EXPECT_TRUE(test::identical_checkpoints(a.last_checkpoint, b.last_checkpoint, &why)) << why;
}

// A restart continues a heat run bit-identically (the temperature, its rates and the compensated
// sum's residual are in the checkpoint).
TEST(Heat, RestartContinuesBitIdentically) {
  const Case c = load_case(test::case_path("conduction_2d.yaml"), {"output.interval=0"});
  RunOptions o;
  o.steps = 120;
  const RunResult straight = test::run_case(c, test::scratch("heat-restart-straight"), o);
  o.steps = 60;
  const RunResult first = test::run_case(c, test::scratch("heat-restart-first"), o);
  o.restart = first.last_checkpoint;  // 60 more
  const RunResult second = test::run_case(c, test::scratch("heat-restart-second"), o);
  ASSERT_EQ(second.exit_code, 0) << second.message;
  const OptionalFields thermal(FieldGroups{kThermal});
  std::string why;
  EXPECT_TRUE(test::identical_checkpoints(straight.last_checkpoint, second.last_checkpoint, &why)) << why;
}

}  // namespace
}  // namespace spate
