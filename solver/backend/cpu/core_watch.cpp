#include "core_watch.hpp"

#include <sched.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <fstream>
#include <string>
#include <thread>

#include "parallel.hpp"

namespace spate::cpu {

std::optional<MachineTicks> read_machine_ticks() {
  std::ifstream in("/proc/stat");
  std::string label;
  if (!(in >> label) || label != "cpu") return std::nullopt;
  // user nice system idle iowait irq softirq steal (guest time is inside user already)
  std::uint64_t field[8] = {};
  for (auto& f : field)
    if (!(in >> f)) return std::nullopt;
  MachineTicks t;
  for (int k = 0; k < 8; ++k) t.total += field[k];
  t.busy = t.total - field[3] - field[4];
  return t;
}

bool fits_in_cores(double machine_busy_cores, double own_busy_cores, int threads, int cores) {
  const double others = std::max(0.0, machine_busy_cores - own_busy_cores);
  return others + threads <= cores + 0.25;
}

namespace {

double own_cpu_seconds() {
  rusage u{};
  if (getrusage(RUSAGE_SELF, &u) != 0) return 0.0;
  auto seconds = [](const timeval& t) { return static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_usec); };
  return seconds(u.ru_utime) + seconds(u.ru_stime);
}

// The cores this process may run on (its affinity mask), else the machine's.
int usable_cores() {
  cpu_set_t allowed;
  if (sched_getaffinity(0, sizeof allowed, &allowed) == 0) return std::max(1, CPU_COUNT(&allowed));
  return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

}  // namespace

CoreWatch::CoreWatch(int threads) : threads_(threads), cores_(usable_cores()), last_(std::chrono::steady_clock::now()) {
  set_cores_free(false);  // safe until measured
  if (threads_ > 1) {
    machine_ = read_machine_ticks();
    own_seconds_ = own_cpu_seconds();
  }
}

void CoreWatch::tick() {
  if (threads_ <= 1 || !machine_) return;
  const auto now = std::chrono::steady_clock::now();
  if (now - last_ < std::chrono::seconds(1)) return;
  last_ = now;
  measure();
}

void CoreWatch::measure() {
  const auto machine = read_machine_ticks();
  const double own = own_cpu_seconds();
  if (!machine || machine->total <= machine_->total) return;
  // Busy cores = busy ticks over all ticks times the machine's cores: the same as per wall second,
  // without asking how long a tick is.
  const long online = sysconf(_SC_NPROCESSORS_ONLN);
  const double machine_cores = online > 0 ? static_cast<double>(online) : static_cast<double>(cores_);
  const double share = static_cast<double>(machine->busy - machine_->busy) / static_cast<double>(machine->total - machine_->total);
  const double ticks_per_second = static_cast<double>(sysconf(_SC_CLK_TCK));
  const double wall = static_cast<double>(machine->total - machine_->total) / (ticks_per_second * machine_cores);
  const double own_cores = wall > 0 ? (own - own_seconds_) / wall : 0.0;
  set_cores_free(fits_in_cores(share * machine_cores, own_cores, threads_, cores_));
  machine_ = machine;
  own_seconds_ = own;
}

}  // namespace spate::cpu
