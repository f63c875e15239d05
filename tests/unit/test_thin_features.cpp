// Thin-feature warnings (solver/case/thin_features.cpp): the wet bed, thin fluid blocks and narrow
// gaps around solids are reported below three particle layers, with the dp that resolves them.
#include <gtest/gtest.h>

#include "../source_dir.hpp"

#include "case/case.hpp"
#include "case/thin_features.hpp"

namespace spate {
namespace {

std::string column_case() { return test::source_dir() + "/cases/dam_break_column_3d.yaml"; }

TEST(ThinFeatures, ColumnCaseWetBedAtDp0015) {
  const Case c = load_case(column_case(), {"dp=0.015"});
  const auto thin = thin_features(c);
  ASSERT_EQ(thin.size(), 1u);
  EXPECT_EQ(thin[0].key, "wet_bed");
  EXPECT_DOUBLE_EQ(thin[0].thickness, 0.01);
  EXPECT_NEAR(thin[0].layers, 0.01 / 0.015, 1e-12);
  EXPECT_NEAR(thin[0].resolving_dp, 0.01 / 3, 1e-12);
  const std::string m = thin[0].message(c.dp);
  EXPECT_NE(m.find("wet bed is 0.01 m deep"), std::string::npos) << m;
  EXPECT_NE(m.find("dp <= 0.00333 m resolves it"), std::string::npos) << m;
  EXPECT_NE(thin_features(load_case(column_case(), {"dp=0.025"}))[0].message(0.025).find("gets no particles"), std::string::npos);
}

TEST(ThinFeatures, ResolvedOrAbsentFeaturesAreQuiet) {
  EXPECT_TRUE(thin_features(load_case(column_case(), {"dp=0.003"})).empty()) << "0.01 m is 3.3 layers at dp = 0.003";
  EXPECT_TRUE(thin_features(load_case(column_case(), {"dp=0.015", "wet_bed=0"})).empty());
}

TEST(ThinFeatures, ThinBlockAndNarrowGaps) {
  const Case c = parse_case(R"(name: gaps
dimensions: 2
dp: 0.01
time: {end: 0.1}
tank: {size: [1.0, 0.5], open_top: false}
fluid_blocks:
  - {min: [0, 0], max: [0.3, 0.02]}
solids:
  - {name: a, min: [0.5, 0], max: [0.6, 0.48]}
  - {name: b, min: [0.62, 0], max: [0.7, 0.3]}
  - {name: c, min: [0.98, 0], max: [1.0, 0.1]}
)",
                            "gaps.yaml");
  std::vector<std::string> keys;
  for (auto& f : thin_features(c)) keys.push_back(f.key + " " + f.what);
  const std::vector<std::string> expected = {
      "fluid_blocks[0] the block is 0.02 m thick along y",
      "solids[0] the gap along y between solid 'a' and the tank wall at y = 0.5 is 0.02 m wide",  // under the lid
      "solids[1] the gap along x between solid 'b' and solid 'a' is 0.02 m wide",
  };
  ASSERT_EQ(keys.size(), expected.size()) << ::testing::PrintToString(keys);
  for (std::size_t k = 0; k < keys.size(); ++k) EXPECT_NE(keys[k].find(expected[k]), std::string::npos) << keys[k];
}

}  // namespace
}  // namespace spate
