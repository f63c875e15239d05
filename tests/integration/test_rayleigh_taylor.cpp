// Rayleigh-Taylor growth against viscous linear theory (issue 35; label `validation`): the
// single-mode interface wave of cases/rayleigh_taylor_linear_2d.yaml (k a0 = 0.047) at two
// resolutions, its amplitude (the interface probe) fitted by the growth-rate analysis that
// `spate growth` and docs/validation.md's figure use (sim/growth.hpp), against
// n = sqrt(A g k + nu^2 k^4) - nu k^2 = 1.249. With eq. 7's symmetric pressure gradient the
// same run grows at 0.69 (docs/studies/rayleigh-taylor.md).
#include <gtest/gtest.h>

#include <cmath>

#include "run_helpers.hpp"
#include "sim/growth.hpp"

namespace spate {
namespace {

TEST(Validation, RayleighTaylorLinearGrowthRate) {
  const double theory = rayleigh_taylor_rate(0.8 / 2.8, 1.0, 2.0 * M_PI, 1.0 / 420.0);
  // lambda / dp = 50 and 80; to t = 1.7, past where the amplitude reaches 4 a0 (k a = 0.19).
  for (const char* dp : {"0.02", "0.0125"}) {
    SCOPED_TRACE(std::string("dp = ") + dp);
    const Case c = load_case(test::case_path("rayleigh_taylor_linear_2d.yaml"), {std::string("dp=") + dp, "time.end=1.7", "output.interval=0"});
    const auto out = test::scratch(std::string("rt-linear-") + dp);
    ASSERT_EQ(test::run_case(c, out).exit_code, 0);
    const auto a = read_probe_column((out / "probes" / "amplitude.csv").string(), "amplitude");
    ASSERT_FALSE(a.empty());
    // The start holds the wave, a fraction of dp, to 10%.
    EXPECT_NEAR(a.front().second, 0.0075, 0.00075);
    const GrowthFit fit = fit_growth(a, 0.03);
    EXPECT_GT(fit.to, 1.5) << "the linear range must be sampled to k a = 0.19";
    EXPECT_LT(fit.rms, 0.02) << "the amplitude must follow a growing and a decaying mode";
    EXPECT_NEAR(fit.rate / theory, 1.0, 0.10) << "fitted " << fit.rate << ", theory " << theory;
  }
}

}  // namespace
}  // namespace spate
