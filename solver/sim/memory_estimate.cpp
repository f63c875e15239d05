#include "memory_estimate.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <fstream>
#include <sstream>

#include "../backend/cuda/device_plan.hpp"
#include "../backend/cuda/device_runtime.hpp"
#include "../case/generator.hpp"
#include "../particles/particle_store.hpp"

namespace spate {

namespace {

// Bytes of one particle's fields (every array of ParticleStore) and of the solver arrays per
// particle (fields + sort words).
std::int64_t field_bytes(int dim) {
  ParticleStore layout(dim);
  std::int64_t b = 0;
  for (auto& f : layout.fields()) b += static_cast<std::int64_t>(f.elem_size);
  return b;
}

// One owned particle in a snapshot piece: the arrays write_vtp_piece builds before writing them
// (velocity, pressure, density, id, kind, slab, point, connectivity and offset) and the slab,
// connectivity and offset sources they are made from.
constexpr std::int64_t kSnapshotBytes = 12 + 4 + 4 + 4 + 1 + 4 + 12 + 8 + 8 + 4 + 8 + 8;
// Per process besides the particles: threads' stacks and buffers, the allocator's slack.
constexpr std::int64_t kProcessOverhead = 96ll << 20;
// Ghosts and the slack of growing arrays: the slab arrays hold up to this much more than the
// owned particles (measured: ghosts are 5-15 % on the shipped cases at 1-4 slabs).
constexpr double kSlabSlack = 1.25;

// "<key> <n> kB" from a /proc file, in bytes; -1 when absent.
std::int64_t read_kib(const char* file, const char* key) {
  std::ifstream in(file);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind(key, 0) != 0) continue;
    std::istringstream s(line.substr(std::string(key).size()));
    std::int64_t kib = 0;
    if (s >> kib) return kib * 1024;
  }
  return -1;
}
std::int64_t read_meminfo(const char* key) { return read_kib("/proc/meminfo", key); }
std::int64_t read_status(const char* key) { return std::max<std::int64_t>(0, read_kib("/proc/self/status", key)); }

std::int64_t read_number(const std::string& path) {
  std::ifstream in(path);
  std::string text;
  if (!(in >> text) || text == "max") return -1;
  try {
    return std::stoll(text);
  } catch (const std::exception&) {
    return -1;
  }
}

// This process's cgroup v2 folder (the line "0::/path" of /proc/self/cgroup), or empty.
std::string cgroup_folder() {
  std::ifstream in("/proc/self/cgroup");
  for (std::string line; std::getline(in, line);)
    if (line.rfind("0::", 0) == 0) return "/sys/fs/cgroup" + line.substr(3);
  return {};
}

}  // namespace

std::int64_t checkpoint_read_bytes(int dim, std::int64_t particles) { return particles * field_bytes(dim); }

MemoryEstimate estimate_run_memory(const Case& c, int ranks, int ranks_on_node) {
  // The case's optional fields (surface tension's, heat transfer's) count, as in its run.
  const OptionalFields optional_fields(FieldGroups{optional_field_groups(physics_params(c))});
  MemoryEstimate e;
  e.particles = count_particles(c).total();
  const double all = static_cast<double>(e.particles);
  const double mine = all / std::max(1, ranks);
  const double fields = static_cast<double>(field_bytes(c.dim));
  const double solver = static_cast<double>(ParticleStore(c.dim).bytes_per_particle());
  // Start: every rank generates the whole set, and its slabs copy their shares out of it (with a
  // 4-byte index each) before it is freed.
  const double start = all * fields + mine * (fields + 4);
  // Running: the slab arrays with ghosts and slack, plus the larger of a snapshot piece being
  // written and the checkpoint writer's part: the other ranks' particles (packed) and a 12-byte
  // id-order entry and a 4-byte field buffer per particle.
  const double running = mine * kSlabSlack * solver +
                         std::max(mine * kSnapshotBytes, (all - mine) * fields + all * 16.0);
  // Measured on the column case, 1 slab (0.7 to 4.2 M particles): 165 bytes per particle above
  // what the process held before the particles; this gives 178.
  e.bytes = static_cast<std::int64_t>(std::ceil((std::max(start, running) + kProcessOverhead) * std::max(1, ranks_on_node)));
  return e;
}

AvailableMemory available_memory() {
  AvailableMemory m{read_meminfo("MemAvailable:"), "available memory (MemAvailable)"};
  if (m.bytes < 0) m = {read_meminfo("MemFree:"), "free memory (MemFree)"};
  auto limit = [&](std::int64_t bytes, const std::string& source) {
    if (bytes >= 0 && (m.bytes < 0 || bytes < m.bytes)) m = {bytes, source};
  };
  if (const std::string cg = cgroup_folder(); !cg.empty()) {
    const std::int64_t max = read_number(cg + "/memory.max"), used = read_number(cg + "/memory.current");
    if (max >= 0) limit(std::max<std::int64_t>(0, max - std::max<std::int64_t>(0, used)), "the cgroup's memory.max");
  }
  const std::int64_t v1 = read_number("/sys/fs/cgroup/memory/memory.limit_in_bytes");
  if (v1 > 0 && v1 < (std::int64_t{1} << 60))
    limit(std::max<std::int64_t>(0, v1 - std::max<std::int64_t>(0, read_number("/sys/fs/cgroup/memory/memory.usage_in_bytes"))),
          "the cgroup's memory.limit_in_bytes");
  rlimit r{};
  if (getrlimit(RLIMIT_AS, &r) == 0 && r.rlim_cur != RLIM_INFINITY)
    limit(std::max<std::int64_t>(0, static_cast<std::int64_t>(r.rlim_cur) - read_status("VmSize:")), "the address-space limit (ulimit -v)");
  if (getrlimit(RLIMIT_DATA, &r) == 0 && r.rlim_cur != RLIM_INFINITY)
    limit(std::max<std::int64_t>(0, static_cast<std::int64_t>(r.rlim_cur) - read_status("VmData:")), "the data-segment limit (ulimit -d)");
  if (m.bytes < 0) m = {std::int64_t{1} << 62, "no known limit"};
  return m;
}

std::optional<double> finest_fitting_dp(const Case& c, std::int64_t bytes, int ranks, int ranks_on_node) {
  Case probe = c;
  auto fits = [&](double dp) {
    probe.dp = dp;
    return estimate_run_memory(probe, ranks, ranks_on_node).bytes <= bytes;
  };
  double coarse = c.dp;
  for (int a = 0; a < c.dim; ++a) coarse = std::max(coarse, c.tank_size[a] / 10);
  if (!fits(coarse)) return std::nullopt;
  // Counts fall as dp grows (up to lattice rounding): bisect on log dp, then keep a dp that fits.
  double lo = c.dp, hi = coarse;
  for (int k = 0; k < 60 && hi / lo > 1.0001; ++k) {
    const double mid = std::sqrt(lo * hi);
    (fits(mid) ? hi : lo) = mid;
  }
  // Three significant digits, rounded up so that the printed value still fits.
  const double scale = std::pow(10.0, std::floor(std::log10(hi)) - 2);
  double shown = std::ceil(hi / scale) * scale;
  while (!fits(shown) && shown < coarse) shown += scale;
  return shown;
}

std::string format_bytes(double bytes) {
  const char* units[] = {"bytes", "KiB", "MiB", "GiB", "TiB", "PiB"};
  int u = 0;
  while (bytes >= 1024 && u < 5) bytes /= 1024, ++u;
  return u == 0 ? fmt::format("{:.0f} bytes", bytes) : fmt::format("{:.1f} {}", bytes, units[u]);
}

void require_memory_for(const Case& c, int ranks, int ranks_on_node) {
  const MemoryEstimate need = estimate_run_memory(c, ranks, ranks_on_node);
  const AvailableMemory have = available_memory();
  if (need.bytes <= have.bytes) return;
  std::string msg = fmt::format("{}: key 'dp': at dp = {} the case has {} particles and the run needs about {} of memory{}, "
                                "more than the {} this machine can give ({})",
                                c.file, c.dp, need.particles, format_bytes(static_cast<double>(need.bytes)),
                                ranks_on_node > 1 ? fmt::format(" ({} ranks on this machine)", ranks_on_node) : "",
                                format_bytes(static_cast<double>(have.bytes)), have.source);
  if (const auto dp = finest_fitting_dp(c, have.bytes, ranks, ranks_on_node)) {
    Case fitting = c;
    fitting.dp = *dp;
    msg += fmt::format("; dp >= {:.3g} fits ({} particles, about {})", *dp, count_particles(fitting).total(),
                       format_bytes(static_cast<double>(estimate_run_memory(fitting, ranks, ranks_on_node).bytes)));
  } else {
    msg += "; not even a coarse dp fits";
  }
  throw CaseError(msg);
}

}  // namespace spate

namespace spate {

void require_device_memory_for(const Case& c, int devices) {
  const auto gpus = gpu::devices();
  if (gpus.empty()) return;  // no device: refused elsewhere
  const auto slabs = gpu::device_memory_per_slab(make_lattice(c), count_particles(c).total(), devices);
  for (const auto& m : slabs) {
    const auto& g = gpus[static_cast<std::size_t>(m.slab) % gpus.size()];
    if (m.bytes <= g.memory_bytes) continue;
    throw CaseError(fmt::format("{}: key 'dp': at dp = {} device slab {} needs about {} of GPU memory, more than GPU {} ({}) has ({}); "
                                "use more --devices or a larger dp",
                                c.file, c.dp, m.slab, format_bytes(static_cast<double>(m.bytes)), g.index, g.name,
                                format_bytes(static_cast<double>(g.memory_bytes))));
  }
}

}  // namespace spate
