// Validation against experiment (label `validation`): the 2D dam-break surge front against
// Martin & Moyce (1952), n^2 = 2, a = 2.25 in (shared/data/validation).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "run_helpers.hpp"

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

TEST(Validation, DamBreak2DSurgeFrontAgainstMartinMoyce) {
  const Case c = load_case(test::case_path("dam_break_2d.yaml"), {"output.interval=0", "time.end=0.24"});
  const auto out = test::scratch("validation-front");
  const RunResult r = test::run_case(c, out);
  ASSERT_EQ(r.exit_code, 0) << r.message;
  const double a = c.fluid_blocks[0].max[0] - c.fluid_blocks[0].min[0];
  const double g = std::fabs(c.gravity[1]);
  const auto front = test::read_probe(out / "probes" / "front.csv", 2);
  const auto experiment = read_experiment("martin_moyce_1952_a2.25in.csv");
  double worst = 0.0;
  for (auto [T, Z] : experiment) {
    if (T > 3.0) break;
    const double t = T / std::sqrt(2 * g / a);
    const double z = interpolate(front, t) / a;
    const double err = (z - Z) / Z;
    worst = std::max(worst, std::fabs(err));
    RecordProperty("T_" + std::to_string(T), std::to_string(err));
    std::printf("T = %.2f  experiment Z = %.3f  spate Z = %.3f  error %+.1f%%\n", T, Z, z, 100 * err);
  }
  std::printf("largest error for T <= 3: %.1f%%\n", 100 * worst);
  EXPECT_LT(worst, VALIDATION_FRONT_TOLERANCE);
}

}  // namespace
}  // namespace spate
