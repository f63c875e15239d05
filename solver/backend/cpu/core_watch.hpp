#pragma once
// Whether this process's OpenMP threads have cores to themselves, measured while it runs: once a
// second, the machine's busy CPU time (/proc/stat) less this process's own (getrusage) is what
// other processes used; if that and this process's threads fit in its cores, the parallel loops'
// grains go low (parallel.hpp), otherwise they stay high. Measuring the others (not the load
// average, which counts this process too) keeps the verdict from flipping with its own grain.
#include <chrono>
#include <cstdint>
#include <optional>

namespace spate::cpu {

// The machine's busy and total CPU time since boot in clock ticks (the first line of /proc/stat;
// idle and iowait are not busy); nullopt where it cannot be read.
struct MachineTicks {
  std::uint64_t busy = 0;
  std::uint64_t total = 0;
};
std::optional<MachineTicks> read_machine_ticks();

// The verdict from one interval's measurements: other processes' busy cores (the machine's busy
// cores less this process's) and this process's threads fit in `cores` with a quarter core to spare.
bool fits_in_cores(double machine_busy_cores, double own_busy_cores, int threads, int cores);

class CoreWatch {
 public:
  // threads: the OpenMP threads of this process's parallel loops (1: nothing to decide).
  explicit CoreWatch(int threads);
  // Cheap every step: a clock read; once a second it measures and sets the grains (set_cores_free).
  void tick();

 private:
  void measure();
  int threads_;
  int cores_;
  std::chrono::steady_clock::time_point last_;
  std::optional<MachineTicks> machine_;
  double own_seconds_ = 0.0;
};

}  // namespace spate::cpu
