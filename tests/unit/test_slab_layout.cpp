// SlabLayout (solver/domain/slab_layout.hpp): uniform split, ownership of columns, balancing.
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>

#include "domain/slab_layout.hpp"

namespace spate {
namespace {

std::vector<std::int64_t> per_slab(const SlabLayout& l, const std::vector<std::int64_t>& weight) {
  std::vector<std::int64_t> out(l.slabs(), 0);
  for (int c = 0; c < static_cast<int>(weight.size()); ++c) out[l.owner_of(c)] += weight[c];
  return out;
}

TEST(SlabLayout, UniformSplitsColumnsEvenly) {
  const SlabLayout l = SlabLayout::uniform(10, 3);
  EXPECT_EQ(l.faces, (std::vector<int>{0, 3, 6, 10}));
  EXPECT_EQ(l.slabs(), 3);
  EXPECT_EQ(l.narrowest(), 3);
  const SlabLayout one = SlabLayout::uniform(7, 1);
  EXPECT_EQ(one.faces, (std::vector<int>{0, 7}));
  EXPECT_EQ(one.narrowest(), 7);
}

TEST(SlabLayout, OwnerOfEveryColumn) {
  const SlabLayout l = SlabLayout::uniform(10, 3);
  const int expected[10] = {0, 0, 0, 1, 1, 1, 2, 2, 2, 2};
  for (int c = 0; c < 10; ++c) EXPECT_EQ(l.owner_of(c), expected[c]) << "column " << c;
  // Columns outside the lattice belong to the edge slabs (the ghost columns of the outer faces).
  EXPECT_EQ(l.owner_of(-1), 0);
  EXPECT_EQ(l.owner_of(10), 2);
  EXPECT_EQ(SlabLayout::uniform(5, 1).owner_of(4), 0);
}

TEST(SlabLayout, BalancedLayoutEvensOutASkewedHistogram) {
  // A dam break at the start: all the particles in the first fifth of the tank.
  std::vector<std::int64_t> weight(100, 10);
  for (int c = 0; c < 20; ++c) weight[c] = 1000;
  const SlabLayout uniform = SlabLayout::uniform(100, 4);
  const SlabLayout balanced = balanced_layout(weight, 4, 3);
  EXPECT_GT(imbalance(per_slab(uniform, weight)), 3.0);
  // Faces sit between columns, so the best split is off by at most one column's weight (1000 of a
  // mean of 5200 here).
  const auto counts = per_slab(balanced, weight);
  const double mean = 20800.0 / 4;
  for (auto n : counts) EXPECT_LE(std::fabs(static_cast<double>(n) - mean), 1000.0);
  EXPECT_LT(imbalance(counts), 1.2);
  EXPECT_EQ(balanced.faces.front(), 0);
  EXPECT_EQ(balanced.faces.back(), 100);
  for (int s = 0; s < balanced.slabs(); ++s) EXPECT_LT(balanced.faces[s], balanced.faces[s + 1]);
  // Deterministic: the same histogram gives the same faces.
  EXPECT_EQ(balanced_layout(weight, 4, 3), balanced);
}

TEST(SlabLayout, BalancedLayoutRespectsMinimumColumns) {
  // Everything in one column: the ideal split is impossible, every slab still gets 3 columns.
  std::vector<std::int64_t> weight(20, 0);
  weight[0] = 1000000;
  const SlabLayout l = balanced_layout(weight, 4, 3);
  EXPECT_GE(l.narrowest(), 3);
  EXPECT_EQ(l.faces.back(), 20);
  // The same with the heap at the far end.
  std::vector<std::int64_t> reversed(weight.rbegin(), weight.rend());
  EXPECT_GE(balanced_layout(reversed, 4, 3).narrowest(), 3);
  // Exactly enough columns.
  EXPECT_EQ(balanced_layout(std::vector<std::int64_t>(12, 1), 4, 3).faces, (std::vector<int>{0, 3, 6, 9, 12}));
}

TEST(SlabLayout, BalancedLayoutRejectsTooFewColumns) {
  EXPECT_THROW(balanced_layout(std::vector<std::int64_t>(5, 1), 2, 3), std::invalid_argument);
}

TEST(SlabLayout, BalancingEvensOutTheSumOfBothPhases) {
  // The column case in miniature: fluid (expensive, one phase) upstream, dry walls (the other
  // phase) downstream. The slabs wait for each other once per step over both phases together
  // (the refresh between them is waited for after the interior fluid pass), so the critical path
  // is the longest slab's wall + fluid time, and the faces even out that sum.
  PhaseCosts c{std::vector<std::int64_t>(30, 0), std::vector<std::int64_t>(30, 0)};
  for (int k = 0; k < 30; ++k) c.wall[k] = 10;
  for (int k = 20; k < 30; ++k) c.wall[k] = 60;  // the obstacle and the far wall
  for (int k = 0; k < 12; ++k) c.fluid[k] = 100;
  const SlabLayout layout = balanced_layout(c, 2, 3);
  const auto wall = slab_totals(layout, c.wall), fluid = slab_totals(layout, c.fluid);
  EXPECT_EQ(critical_path(layout, c), std::max(wall[0] + fluid[0], wall[1] + fluid[1]));
  // Within one column of the even split (total 2100: 1050 each; the dearest column costs 110).
  EXPECT_LE(critical_path(layout, c), 1050 + 110);
  // No single-column move of the face shortens it further.
  for (const int delta : {-1, 1}) {
    SlabLayout trial = layout;
    trial.faces[1] += delta;
    EXPECT_GE(critical_path(trial, c), critical_path(layout, c));
  }
  EXPECT_EQ(balanced_layout(c, 2, 3), layout);  // deterministic
  EXPECT_GE(balanced_layout(c, 4, 3).narrowest(), 3);
  // Imbalance: the critical path over the mean total; 1 when every slab's sum is even, even if
  // its phases are not.
  PhaseCosts even{std::vector<std::int64_t>(12, 5), std::vector<std::int64_t>(12, 7)};
  EXPECT_DOUBLE_EQ(phase_imbalance(SlabLayout::uniform(12, 3), even), 1.0);
  EXPECT_EQ(slab_totals(SlabLayout::uniform(12, 3), even.fluid), (std::vector<std::int64_t>{28, 28, 28}));
  PhaseCosts mixed{{0, 0, 0, 12, 12, 12}, {12, 12, 12, 0, 0, 0}};
  EXPECT_DOUBLE_EQ(phase_imbalance(SlabLayout{{0, 3, 6}}, mixed), 1.0);
  EXPECT_DOUBLE_EQ(phase_imbalance(SlabLayout{{0, 2, 6}}, mixed), 48.0 / 36.0);
}

TEST(SlabLayout, ImbalanceIsMaxOverMean) {
  EXPECT_DOUBLE_EQ(imbalance({10, 10, 10}), 1.0);
  EXPECT_DOUBLE_EQ(imbalance({30, 0, 0}), 3.0);
  EXPECT_DOUBLE_EQ(imbalance({}), 1.0);
  EXPECT_DOUBLE_EQ(imbalance({0, 0}), 1.0);
}

}  // namespace
}  // namespace spate
