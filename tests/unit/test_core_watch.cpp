// CoreWatch (backend/cpu/core_watch.hpp): the verdict that sets the parallel loops' grains.
#include <gtest/gtest.h>

#include "backend/cpu/core_watch.hpp"
#include "backend/cpu/parallel.hpp"

namespace spate::cpu {
namespace {

TEST(CoreWatch, OtherProcessesAreTheMachinesBusyCoresLessThisOnes) {
  // 2 cores, 2 threads: free when nobody else runs, whether this process runs serial (1 busy
  // core) or in parallel (2); busy when another process keeps a core, even while this one's own
  // use shrinks because it shares (machine 2 busy, own 1.2).
  EXPECT_TRUE(fits_in_cores(1.0, 1.0, 2, 2));
  EXPECT_TRUE(fits_in_cores(2.0, 2.0, 2, 2));
  EXPECT_TRUE(fits_in_cores(0.2, 1.0, 2, 2));  // the measurements' jitter: own above the machine's
  EXPECT_FALSE(fits_in_cores(2.0, 1.0, 2, 2));
  EXPECT_FALSE(fits_in_cores(2.0, 1.2, 2, 2));
  // 8 cores, 4 threads, another run with 4: fits; with 5: does not.
  EXPECT_TRUE(fits_in_cores(8.0, 4.0, 4, 8));
  EXPECT_FALSE(fits_in_cores(8.0, 3.0, 4, 8));
}

TEST(CoreWatch, ReadsTheMachinesTicks) {
  const auto a = read_machine_ticks();
  ASSERT_TRUE(a.has_value()) << "/proc/stat";
  EXPECT_GT(a->total, 0u);
  EXPECT_LE(a->busy, a->total);
}

TEST(CoreWatch, AFixedVerdictHoldsAndAOneThreadRunChangesNothing) {
  fix_cores_free(true);
  CoreWatch watch(2);  // would start safe (busy) if not fixed
  EXPECT_TRUE(cores_free());
  EXPECT_EQ(pair_grain(), kFreePairGrain);
  fix_cores_free(false);
  EXPECT_EQ(cheap_grain(), kBusyCheapGrain);
  fix_cores_free(std::nullopt);
  CoreWatch single(1);
  single.tick();
  EXPECT_FALSE(cores_free());
}

}  // namespace
}  // namespace spate::cpu
