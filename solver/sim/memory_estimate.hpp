#pragma once
// The host memory a run needs, estimated from the particle count before anything is allocated, and
// the memory the machine can give: a run that would not fit is refused as bad input (exit 2) with
// the estimate and the finest dp that fits, instead of dying of std::bad_alloc minutes later.
#include <cstdint>
#include <optional>
#include <string>

#include "../case/case.hpp"

namespace spate {

struct MemoryEstimate {
  std::int64_t particles = 0;
  std::int64_t bytes = 0;  // peak host memory of all spate processes on this machine
};

// `ranks`: MPI ranks of the run; `ranks_on_node`: those sharing this machine's memory.
MemoryEstimate estimate_run_memory(const Case& c, int ranks = 1, int ranks_on_node = 1);
// The same for a checkpoint of `particles` particles being read (restart, compare).
std::int64_t checkpoint_read_bytes(int dim, std::int64_t particles);

struct AvailableMemory {
  std::int64_t bytes = 0;
  std::string source;  // what limits it: "MemAvailable", "cgroup memory.max", "ulimit -v", ...
};
// The least of: the kernel's MemAvailable, the cgroup's memory limit less its usage, and the
// address-space and data limits (ulimit -v, -d) less what this process already maps.
AvailableMemory available_memory();

// The smallest dp (the finest resolution) at which the case fits into `bytes`, or none when even a
// spacing of a tenth of the tank does not.
std::optional<double> finest_fitting_dp(const Case& c, std::int64_t bytes, int ranks = 1, int ranks_on_node = 1);

// Throws CaseError naming the case file, dp, the estimate, the available memory and the finest dp
// that fits, when the run would not fit.
void require_memory_for(const Case& c, int ranks = 1, int ranks_on_node = 1);

// The same for the device memory of --backend cuda: every GPU must hold its slab (device_plan.hpp).
void require_device_memory_for(const Case& c, int devices);

std::string format_bytes(double bytes);  // "1.5 GiB"

}  // namespace spate
