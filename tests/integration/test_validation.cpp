// Validation against experiment (label `validation`, data from shared/data/validation): the 2D
// dam-break surge front against Martin & Moyce (1952), n^2 = 2, a = 2.25 in; the impact pressures
// of Lobovsky et al. (2014, sensors 1, 3, 4) and Buchner (2002) on the far wall of a dam break;
// the rising bubble of Hysing et al. (2009, test case 1) with surface tension.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <sstream>

#include "run_helpers.hpp"
#include "physics/kernels.hpp"
#include "sim/probes.hpp"

namespace spate {
namespace {

std::vector<std::pair<double, double>> read_experiment(const std::string& file) {
  std::ifstream in(std::string(SPATE_VALIDATION_DIR) + "/" + file);
  std::vector<std::pair<double, double>> out;
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#' || line[0] == 'T') continue;
    std::stringstream s(line);
    std::string t, z;
    std::getline(s, t, ',');
    std::getline(s, z, ',');
    out.emplace_back(std::stod(t), std::stod(z));
  }
  return out;
}

double interpolate(const std::vector<std::pair<double, double>>& series, double t) {
  for (std::size_t k = 1; k < series.size(); ++k)
    if (series[k].first >= t) {
      const auto [t0, v0] = series[k - 1];
      const auto [t1, v1] = series[k];
      return v0 + (v1 - v0) * (t - t0) / (t1 - t0);
    }
  return series.back().second;
}

// Least-squares slope dZ/dT of the points with T in [from, to].
double slope(const std::vector<std::pair<double, double>>& pts, double from, double to) {
  double n = 0, st = 0, sz = 0, stt = 0, stz = 0;
  for (auto [t, z] : pts)
    if (t >= from && t <= to) n += 1, st += t, sz += z, stt += t * t, stz += t * z;
  return (n * stz - st * sz) / (n * stt - st * st);
}

// The surge front of the ideal (instant) release runs ahead of Martin & Moyce by 11-18% for T <= 3
// at every resolution from a/28.6 on, with the experiment's front speed: the lead is a constant
// delay, the time the experiment took to release its column (about 0.25 in T, 13 ms), not too
// little dissipation or too much wall friction, which would change the speed
// (docs/studies/dam-break-front.md, "Why the front is early"). The test asserts exactly that: the
// speed over 1.5 <= T <= 3 within 4%; after the best delay in [0, 0.6] the front within 2.5%
// (rms); that delay between 0.15 and 0.35; and, as before, the raw lead below 19% (17.5% measured).
TEST(Validation, DamBreak2DSurgeFrontAgainstMartinMoyce) {
  const Case c = load_case(test::case_path("dam_break_2d.yaml"), {"output.interval=0", "time.end=0.24"});
  const auto out = test::scratch("validation-front");
  const RunResult r = test::run_case(c, out);
  ASSERT_EQ(r.exit_code, 0) << r.message;
  const double a = c.fluid_blocks[0].max[0] - c.fluid_blocks[0].min[0];
  const double g = std::fabs(c.gravity[1]);
  const double T_of_t = std::sqrt(2 * g / a);
  std::vector<std::pair<double, double>> front;  // (T, Z)
  for (auto [t, x] : test::read_probe(out / "probes" / "front.csv", 2)) front.emplace_back(t * T_of_t, x / a);
  std::vector<std::pair<double, double>> experiment;
  for (auto p : read_experiment("martin_moyce_1952_a2.25in.csv"))
    if (p.first <= 3.0) experiment.push_back(p);
  double worst = 0.0;
  for (auto [T, Z] : experiment) {
    const double err = (interpolate(front, T) - Z) / Z;
    worst = std::max(worst, std::fabs(err));
    std::printf("T = %.2f  experiment Z = %.3f  spate Z = %.3f  error %+.1f%%\n", T, Z, interpolate(front, T), 100 * err);
  }
  double best_rms = INFINITY, best_delay = 0.0;
  for (int k = 0; k <= 60; ++k) {
    const double delay = 0.01 * k;
    double sum = 0.0;
    for (auto [T, Z] : experiment) sum += std::pow((interpolate(front, T - delay) - Z) / Z, 2);
    const double rms = std::sqrt(sum / static_cast<double>(experiment.size()));
    if (rms < best_rms) best_rms = rms, best_delay = delay;
  }
  const double speed = slope(front, 1.5, 3.0), measured = slope(experiment, 1.5, 3.0);
  std::printf("largest error for T <= 3: %.1f%%; front speed dZ/dT over 1.5 <= T <= 3: %.3f (experiment %.3f, %+.1f%%); "
              "after a release delay of %.2f (%.1f ms): rms %.1f%%\n",
              100 * worst, speed, measured, 100 * (speed / measured - 1), best_delay, 1e3 * best_delay / T_of_t, 100 * best_rms);
  EXPECT_LT(worst, 0.19);
  EXPECT_LT(std::fabs(speed / measured - 1), 0.04);
  EXPECT_LT(best_rms, 0.025);
  EXPECT_GE(best_delay, 0.15);
  EXPECT_LE(best_delay, 0.35);
}

// A pressure record in the experiments' units: tau = t sqrt(g/H), P = p / (rho g H), by time.
using Record = std::vector<std::pair<double, double>>;

// The trailing moving average over `window` (in tau) of a record, sample by sample: the averaging a
// sensor with that window applies (sim/probes.hpp MovingAverage), so that spate's sensors and the
// experiment are compared through the same filter.
Record averaged(const Record& r, double window) {
  MovingAverage a(window);
  Record out;
  for (auto [t, v] : r) out.emplace_back(t, a.add(t, v));
  return out;
}

// What the tests compare (docs/studies/impact-pressures.md):
//   arrival   the first of three consecutive samples above 0.3 rho g H (the data are noisy before);
//   peak      the largest value within one tau after the arrival (the first impact);
//   plateau   the mean over 1 <= tau - tau_arrival <= 2 (the record linear between samples);
//   lowest    the smallest value after the arrival (tension shows as negative pressure).
struct Impact {
  double arrival = NAN, peak = NAN, plateau = NAN, lowest = NAN;
};

Impact impact_of(const Record& r) {
  Impact m;
  for (std::size_t k = 0; k + 2 < r.size(); ++k)
    if (r[k].second > 0.3 && r[k + 1].second > 0.3 && r[k + 2].second > 0.3) {
      m.arrival = r[k].first;
      break;
    }
  if (std::isnan(m.arrival)) return m;
  m.peak = -INFINITY, m.lowest = INFINITY;
  for (auto [t, v] : r) {
    if (t >= m.arrival && t <= m.arrival + 1) m.peak = std::max(m.peak, v);
    if (t >= m.arrival) m.lowest = std::min(m.lowest, v);
  }
  const double from = m.arrival + 1, to = m.arrival + 2;
  double integral = 0.0;
  for (std::size_t k = 1; k < r.size(); ++k) {
    const auto [t0, v0] = r[k - 1];
    const auto [t1, v1] = r[k];
    const double a = std::max(t0, from), b = std::min(t1, to);
    if (b <= a || t1 <= t0) continue;
    const auto at = [&](double t) { return v0 + (v1 - v0) * (t - t0) / (t1 - t0); };
    integral += 0.5 * (at(a) + at(b)) * (b - a);
  }
  m.plateau = r.back().first >= to ? integral / (to - from) : NAN;
  return m;
}

// The digitised experiment, sorted by time (the digitisation lists a few points out of order), its
// clock moved by `shift` (tau; lobovsky_clock_offset below).
Record experiment_record(const std::string& file, double shift = 0.0) {
  Record r = read_experiment(file);
  for (auto& [t, v] : r) t += shift;
  std::stable_sort(r.begin(), r.end(), [](auto& a, auto& b) { return a.first < b.first; });
  return r;
}

// The acceptance levels (issue 11), and where spate does not reach one the level it does
// reach, so that a regression shows (docs/studies/impact-pressures.md says which and why).
struct Tolerance {
  double arrival_s = 0.02;  // |arrival - experiment| [s]
  double peak = 0.25;       // |peak / experiment - 1|, both through the sensor's window
  double plateau = 0.10;    // |plateau / experiment - 1| (NAN: not checked, the run ends before)
  double lowest = -0.1;     // the sensor's reading after the arrival, at least this [rho g H]
};

struct Sensor {
  std::string probe, data;
  Tolerance tol = {};
};

// Runs a dam-break case and checks each of its sensors against the experiment, both through the
// sensor's window (the sensor averages itself; the experiment is averaged here the same way).
// `shift` [tau] moves the experiment's clock (the level records' clock of lobovsky_clock_offset).
// `sets`: case keys the run changes (--set), `tag` names its scratch folder apart. Returns the
// finished run's folder.
std::filesystem::path check_impacts(const std::string& case_file, double H, const std::vector<Sensor>& sensors, double end_time,
                                    double shift = 0.0, std::vector<std::string> sets = {}, const std::string& tag = "") {
  sets.push_back("output.interval=0");
  sets.push_back("time.end=" + std::to_string(end_time));
  const Case c = load_case(test::case_path(case_file), sets);
  const auto out = test::scratch("validation-" + c.name + tag);
  const RunResult r = test::run_case(c, out);
  EXPECT_EQ(r.exit_code, 0) << r.message;
  if (r.exit_code != 0) return out;
  const double g = std::fabs(c.gravity[c.dim - 1]);
  const double tau = std::sqrt(g / H), rho_g_h = c.fluids[0].density * g * H;
  for (const Sensor& s : sensors) {
    const auto spec = std::find_if(c.probes.begin(), c.probes.end(), [&](auto& p) { return p.name == s.probe; });
    EXPECT_NE(spec, c.probes.end()) << s.probe;
    if (spec == c.probes.end()) continue;
    EXPECT_GT(spec->window, 0.0) << s.probe << ": the comparison is through the sensor's window";
    Record sim;
    for (auto [t, p] : test::read_probe(out / "probes" / (s.probe + ".csv"), 2)) sim.emplace_back(t * tau, p / rho_g_h);
    const Impact e = impact_of(averaged(experiment_record(s.data, shift), spec->window * tau));
    const Impact m = impact_of(sim);
    std::printf("%s %s: arrival tau %.3f (experiment %.3f, %+.1f ms), peak %.3f (%.3f, %+.0f%%), plateau %.3f (%.3f, %+.1f%%), "
                "lowest after arrival %+.3f rho g H\n",
                c.name.c_str(), s.probe.c_str(), m.arrival, e.arrival, 1e3 * (m.arrival - e.arrival) / tau, m.peak, e.peak,
                100 * (m.peak / e.peak - 1), m.plateau, e.plateau, 100 * (m.plateau / e.plateau - 1), m.lowest);
    EXPECT_LE(std::fabs(m.arrival - e.arrival) / tau, s.tol.arrival_s) << s.probe << ": arrival";
    EXPECT_LE(std::fabs(m.peak / e.peak - 1), s.tol.peak) << s.probe << ": first peak";
    if (!std::isnan(s.tol.plateau)) {
      EXPECT_LE(std::fabs(m.plateau / e.plateau - 1), s.tol.plateau) << s.probe << ": plateau";
    }
    EXPECT_GE(m.lowest, s.tol.lowest) << s.probe << ": tension after the impact";
  }
  return out;
}

// The default scheme (delta-SPH after Fourtakas, central pressure term) with the instant release,
// against the records as published, meets the levels except where a Tolerance below says
// otherwise: the first peak at p1 (+72%; +41% converged), a dip to -0.21 rho g H at p3 just after
// the arrival, and the late rise at p4 (arrival +56 ms, plateau -12%). The experiment's level
// records show why (docs/studies/impact-pressures.md, "The release: a lifted gate, and the experiment's two
// clocks"): the instant release's thin tip reaches the wall 37 ms before the experiment's surge,
// and the pressure records' clock starts 45 ms after the experiment's release, so p1 and p3 look on
// time and p4 late. LobovskyGateRelease below compares the released-by-a-gate case on one clock.
TEST(Validation, LobovskyImpactPressures) {
  Tolerance p1, p3, p4;
  p1.peak = 0.85;      // +72%
  p3.lowest = -0.3;    // -0.21
  p4.arrival_s = 0.07; // +56 ms
  p4.plateau = 0.15;   // -12%
  check_impacts("dam_break_lobovsky.yaml", 0.3,
                {{"p1", "lobovsky_2014_p1.csv", p1}, {"p3", "lobovsky_2014_p3.csv", p3}, {"p4", "lobovsky_2014_p4.csv", p4}}, 1.0);
}

// Buchner's sensor where the experiment had it, centred at 160 mm (0.267 H), 90 mm across
// (docs/studies/buchner-sensor-height.md). The water takes no tension (the case's
// `fluid.tension: false`): arrival -3.6 ms, first peak -16%, plateau -14% (with tension the thin
// run-up sheet pulled on the wall and the sensor rose +159 ms late, peak -27%, plateau -17%;
// docs/studies/buchner-run-up.md). The plateau still misses issue 11's 10% (issue 33).
TEST(Validation, BuchnerImpactPressure) {
  Tolerance p1;
  p1.plateau = 0.17;  // -14%
  check_impacts("dam_break_buchner_2d.yaml", 0.6, {{"p1", "buchner_2002_pressure.csv", p1}}, 1.35);
}

// Lobovsky et al. (2014, Fig. 16, H = 300 mm): the water-level gauges H2-H4, where they stand [m]
// and when the surge first reads 0.02 H there, the mean of the paper's two records [tau]
// (lobovsky_2014_levels.csv, which scripts/studies/impact_metrics.py reads too).
struct LevelGauge {
  std::string probe;
  double x, first_reading;
};
std::vector<LevelGauge> lobovsky_gauges() {
  std::ifstream in(std::string(SPATE_VALIDATION_DIR) + "/lobovsky_2014_levels.csv");
  std::vector<LevelGauge> out;
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#' || line.rfind("gauge", 0) == 0) continue;
    std::stringstream s(line);
    std::string name, x, a, b;
    std::getline(s, name, ',');
    std::getline(s, x, ',');
    std::getline(s, a, ',');
    std::getline(s, b, ',');
    out.push_back({name, std::stod(x), (std::stod(a) + std::stod(b)) / 2});
  }
  return out;
}

// How much later [tau] the experiment's pressure records start their clock than its level records:
// the surge, continued from H4 to the end wall (1.61 m) at the speed it had from H3 to H4, reaches
// the wall at 2.686 on the level clock, and p1 rises at 2.427 on the pressure clock. Nothing of
// spate's goes into it (docs/studies/impact-pressures.md, "The release: a lifted gate, and the experiment's
// two clocks").
double lobovsky_clock_offset() {
  const std::vector<LevelGauge> gauges = lobovsky_gauges();
  EXPECT_EQ(gauges.size(), 3u) << "lobovsky_2014_levels.csv: h2, h3, h4";
  if (gauges.size() != 3) return NAN;
  const LevelGauge &h3 = gauges[1], &h4 = gauges[2];
  const double at_wall = h4.first_reading + (h4.first_reading - h3.first_reading) * (1.61 - h4.x) / (h4.x - h3.x);
  return at_wall - impact_of(experiment_record("lobovsky_2014_p1.csv")).arrival;
}

// The column released as the experiment released it, by a gate lifted from the floor
// (cases/dam_break_lobovsky_gate.yaml). The surge passes the level gauges H2-H4 as the records do
// (+0.006 / -0.023 / +0.020 tau; the instant release -0.05 / -0.15 / -0.16), and on the level
// records' clock the pressures arrive within 0.02 s at every sensor (+4.4 / +2.6 / +2.7 ms), the
// first peaks are within 25% (+14 / +2 / -1%), and nothing reads below -0.1 rho g H after the
// arrival (+0.32 / +0.32 / +0.30). The run stops at t = 0.75 s, before the plateaus (the full run:
// -5 / -12 / -15%; docs/studies/impact-pressures.md).
TEST(Validation, LobovskyGateRelease) {
  Tolerance p1, p3, p4;
  p1.plateau = p3.plateau = p4.plateau = NAN;
  const double shift = lobovsky_clock_offset();
  EXPECT_NEAR(shift, 0.259, 0.001) << "the gauges' numbers or the p1 record changed";
  const auto out = check_impacts("dam_break_lobovsky_gate.yaml", 0.3,
                                 {{"p1", "lobovsky_2014_p1.csv", p1}, {"p3", "lobovsky_2014_p3.csv", p3}, {"p4", "lobovsky_2014_p4.csv", p4}},
                                 0.75, shift);
  const double tau = std::sqrt(9.81 / 0.3);
  for (const LevelGauge& g : lobovsky_gauges()) {
    double first = NAN;
    for (auto [t, h] : test::read_probe(out / "probes" / (g.probe + ".csv"), 2))
      if (h > 0.02 * 0.3) {
        first = t * tau;
        break;
      }
    std::printf("dam_break_lobovsky_gate %s: the surge first reads 0.02 H at tau %.3f (experiment %.3f, %+.3f)\n", g.probe.c_str(),
                first, g.first_reading, first - g.first_reading);
    EXPECT_NEAR(first, g.first_reading, 0.06) << g.probe;
  }
}

// The smooth floor's turbulent shear (tank.wall_shear: log_law) in place of the artificial
// viscosity's friction against the walls (fluid.wall_artificial_viscosity: 0), the gated case at
// H/60 on the level records' clock: arrivals -9.7 / -14.1 / -22.8 ms, first peaks +37 / +5 / -8%,
// plateaus +24.5 / +23.4 / -13.3%, nothing below +0.2 rho g H after the arrivals. Less friction than
// the artificial one at this dp, more than none (plateaus +51 / +38 / -19% without any): the
// tolerances hold it between. As dp halves its plateaus move towards the experiment (+12.7 / +0.1 /
// -0.5% at H/240) without settling there: the corner eddy returns at H/240 (docs/studies/impact-pressures.md,
// "Why the log law's plateaus still move with dp").
TEST(Validation, LobovskyGateLogLawFloor) {
  Tolerance p1, p3, p4;
  p1.arrival_s = p3.arrival_s = p4.arrival_s = 0.03;  // -23 ms at p4
  p1.peak = 0.5;                                      // +37%
  p1.plateau = p3.plateau = 0.35;                     // +24.5%, +23.4% (+51%, +38% without friction)
  p4.plateau = 0.17;                                  // -13.3% (-19% without friction)
  p1.lowest = p3.lowest = p4.lowest = 0.1;            // +0.35, +0.27, +0.22
  check_impacts("dam_break_lobovsky_gate.yaml", 0.3,
                {{"p1", "lobovsky_2014_p1.csv", p1}, {"p3", "lobovsky_2014_p3.csv", p3}, {"p4", "lobovsky_2014_p4.csv", p4}}, 0.92,
                lobovsky_clock_offset(), {"fluid.wall_artificial_viscosity=0", "tank.wall_shear=log_law"}, "-log-law");
}

// The circularity of a 2D blob of particles (Hysing et al. 2009): the perimeter of the circle of
// the blob's area over the blob's perimeter (1 for a disc, less for any other shape). The area is
// the particles' count times dp^2; the perimeter that of the 0.5 contour of the colour field
// c(x) = sum_j dp^2 W(x - x_j) over the blob's particles (Wendland C2, smoothing length h),
// sampled every dp/4 and traced by marching squares.
double circularity(const std::vector<std::array<double, 2>>& x, double dp, double h) {
  if (x.empty()) return 0.0;
  double lo[2] = {x[0][0], x[0][1]}, hi[2] = {x[0][0], x[0][1]};
  for (auto& q : x)
    for (int a = 0; a < 2; ++a) lo[a] = std::min(lo[a], q[a]), hi[a] = std::max(hi[a], q[a]);
  const double s = dp / 4, pad = 2 * h + 2 * s;
  const int nx = static_cast<int>((hi[0] - lo[0] + 2 * pad) / s) + 1, ny = static_cast<int>((hi[1] - lo[1] + 2 * pad) / s) + 1;
  const double ox = lo[0] - pad, oy = lo[1] - pad;
  std::vector<double> c(static_cast<std::size_t>(nx) * ny, 0.0);
  const float norm = WendlandC2::normalisation(2, static_cast<float>(h));
  const int reach = static_cast<int>(2 * h / s) + 1;
  for (auto& q : x) {
    const int ix = static_cast<int>((q[0] - ox) / s), iy = static_cast<int>((q[1] - oy) / s);
    for (int j = std::max(0, iy - reach); j <= std::min(ny - 1, iy + reach); ++j)
      for (int i = std::max(0, ix - reach); i <= std::min(nx - 1, ix + reach); ++i) {
        const double r = std::hypot(ox + i * s - q[0], oy + j * s - q[1]);
        if (r < 2 * h) c[static_cast<std::size_t>(j) * nx + i] += dp * dp * WendlandC2::value(static_cast<float>(r / h), norm);
      }
  }
  // Marching squares: where the 0.5 contour crosses the cell's edges (linear interpolation), one
  // segment per pair of crossings (a saddle's two pairs in edge order: the length is the same).
  double perimeter = 0.0;
  auto at = [&](int i, int j) { return c[static_cast<std::size_t>(j) * nx + i] - 0.5; };
  for (int j = 0; j + 1 < ny; ++j)
    for (int i = 0; i + 1 < nx; ++i) {
      const double v[4] = {at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)};
      const double px[4] = {0, s, s, 0}, py[4] = {0, 0, s, s};
      std::vector<std::array<double, 2>> cross;
      for (int e = 0; e < 4; ++e) {
        const int f = (e + 1) % 4;
        if ((v[e] < 0) != (v[f] < 0)) {
          const double t = v[e] / (v[e] - v[f]);
          cross.push_back({px[e] + t * (px[f] - px[e]), py[e] + t * (py[f] - py[e])});
        }
      }
      for (std::size_t k = 0; k + 1 < cross.size(); k += 2)
        perimeter += std::hypot(cross[k + 1][0] - cross[k][0], cross[k + 1][1] - cross[k][1]);
    }
  const double area = static_cast<double>(x.size()) * dp * dp;
  return perimeter > 0 ? 2 * std::sqrt(M_PI * area) / perimeter : 0.0;
}

// The circularity measure itself: a disc of particles on the lattice (a staircase circle) reads 1
// within 2% (measured 0.987); a square sqrt(pi)/2 = 0.886, a little more as the contour rounds
// its corners over about h (measured 0.917 at 16 x 16 particles).
TEST(Validation, CircularityOfALatticeDiscIsOne) {
  const double dp = 0.025, h = 1.3 * dp;
  std::vector<std::array<double, 2>> disc, square;
  for (int j = -20; j <= 20; ++j)
    for (int i = -20; i <= 20; ++i) {
      const double x = (i + 0.5) * dp, y = (j + 0.5) * dp;
      if (x * x + y * y < 0.25 * 0.25) disc.push_back({x, y});
      if (std::fabs(x) < 0.2 && std::fabs(y) < 0.2) square.push_back({x, y});
    }
  EXPECT_NEAR(circularity(disc, dp, h), 1.0, 0.02);
  EXPECT_GT(circularity(square, dp, h), std::sqrt(M_PI) / 2);
  EXPECT_LT(circularity(square, dp, h), 0.93);
}

// Hysing et al. (2009), test case 1 (cases/bubble_rise_2d.yaml, surface tension sigma = 24.5,
// free-slip sides): the rise velocity's maximum, 0.2417 at t = 0.9213, and the centroid height at
// t = 3, 1.0813, within 5% (measured at dp = 1/40: 0.2392, -1.0%, and 1.0852, +0.4%). The maximum
// comes late (measured t = 1.16) and the velocity then decays faster than the centroid alone would
// tell (docs/studies/rising-bubble.md): its time is asserted within 0.4 only. The
// circularity at t = 3 (measured 0.921; the reference's minimum 0.9013 at t = 1.9) is printed and
// must stay above 0.85 (a bubble that broke up or flattened reads far less).
TEST(Validation, BubbleRiseAgainstHysing) {
  Case c = load_case(test::case_path("bubble_rise_2d.yaml"));
  c.output_interval = 0.0;
  const auto out = test::scratch("bubble-rise");
  RunOptions o;
  o.threads = 2;
  const RunResult r = test::run_case(c, out, o);
  ASSERT_EQ(r.exit_code, 0) << r.message;
  const auto y = test::read_probe(out / "probes" / "bubble.csv", 3);
  const auto vy = test::read_probe(out / "probes" / "bubble.csv", 5);
  ASSERT_FALSE(vy.empty());
  const auto peak = *std::max_element(vy.begin(), vy.end(), [](auto a, auto b) { return a.second < b.second; });
  const double y3 = interpolate(y, 3.0);
  ParticleStore p;
  read_checkpoint(r.last_checkpoint, p);
  std::vector<std::array<double, 2>> bubble;
  for (std::size_t i = 0; i < p.size(); ++i)
    if (p.material[i] == 1) bubble.push_back({p.pos[0][i], p.pos[1][i]});
  const double circ = circularity(bubble, c.dp, c.smoothing_ratio * c.dp);
  std::printf("bubble rise: max rise velocity %.4f at t = %.3f (Hysing 0.2417 at 0.9213, %+.1f%%), centroid at t = 3 %.4f "
              "(1.0813, %+.1f%%), circularity at t = 3 %.3f\n",
              peak.second, peak.first, 100 * (peak.second / 0.2417 - 1), y3, 100 * (y3 / 1.0813 - 1), circ);
  EXPECT_NEAR(peak.second, 0.2417, 0.05 * 0.2417) << "rise velocity maximum";
  EXPECT_NEAR(peak.first, 0.9213, 0.4) << "time of the rise velocity maximum";
  EXPECT_NEAR(y3, 1.0813, 0.05 * 1.0813) << "centroid height at t = 3";
  EXPECT_GT(circ, 0.85) << "circularity at t = 3";
}

// The demo's load (issue 33): the pressure force of the surge on the column of
// cases/dam_break_column_3d.yaml at the demo's dp = 2 cm. The water takes no tension there
// (`fluid.tension: false`), so the acoustic rebound off the column face cannot pull on it: with
// tension the force swung to -13% of its first peak (-19% at dp = 1.4 cm). No experiment records
// this load; the first peak and the 0.35-0.45 s mean are held to what dp = 1.4 cm gives
// (92 N and 34 N against 120 N and 32 N here; docs/validation.md, "Loads on the column").
TEST(Validation, ColumnLoadHasNoPullAfterTheImpact) {
  const Case c = load_case(test::case_path("dam_break_column_3d.yaml"),
                           {"dp=0.02", "wet_bed=0", "time.dt=auto", "time.end=0.45", "output.interval=0"});
  const auto out = test::scratch("column-load");
  ASSERT_EQ(test::run_case(c, out).exit_code, 0);
  const auto fx = test::read_probe(out / "probes" / "column_force.csv", 2);
  std::size_t onset = 0;
  while (onset < fx.size() && fx[onset].second < 5.0) ++onset;
  ASSERT_LT(onset, fx.size()) << "the surge never reached the column";
  EXPECT_NEAR(fx[onset].first, 0.26, 0.02) << "arrival at the column";
  double peak = 0.0, peak_t = 0.0;
  for (std::size_t k = onset; k < fx.size() && fx[k].first <= fx[onset].first + 0.03; ++k)
    if (fx[k].second > peak) peak = fx[k].second, peak_t = fx[k].first;
  double lowest = peak, mean = 0.0;
  int n = 0;
  for (const auto& [t, f] : fx) {
    if (t >= peak_t && t <= peak_t + 0.15) lowest = std::min(lowest, f);
    if (t >= 0.35 && t <= 0.45) mean += f, ++n;
  }
  ASSERT_GT(n, 0);
  mean /= n;
  EXPECT_GT(lowest, -0.05 * peak) << "the force pulls on the column after its first peak " << peak << " N";
  EXPECT_NEAR(peak, 100.0, 35.0) << "first peak";
  EXPECT_NEAR(mean, 33.0, 6.0) << "mean load 0.35-0.45 s";
}

}  // namespace
}  // namespace spate
