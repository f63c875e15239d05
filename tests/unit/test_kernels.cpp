#include <gtest/gtest.h>

#include "physics/kernels.hpp"

TEST(Kernels, Placeholder) { EXPECT_GT(spate::WendlandC2::normalisation(3, 1.0f), 0.0f); }
