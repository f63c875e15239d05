#pragma once
// Probes written as CSV time series (probes/<name>.csv): pressure at a point (Shepard average of the
// fluid), water height at a gauge, total pressure force on a named solid, surge-front position.
// Sampling is collective; every value is independent of the split (owner-computed or exact).
#include <cstdint>
#include <filesystem>
#include <optional>
#include <vector>

#include "../case/case.hpp"
#include "../io/output_file.hpp"
#include "slab_worker.hpp"

namespace spate {

class ProbeSet {
 public:
  // `writer`: this slab writes the files. `resume_step`: continue existing files after a restart
  // from that step (their rows of later steps, written by the run that went on past the
  // checkpoint, are dropped); none: start them afresh.
  ProbeSet(const Case& c, const std::filesystem::path& out_dir, bool writer, std::optional<std::int64_t> resume_step);
  // Collective over all slabs. Returns the sampled row values in probe order (for tests).
  std::vector<std::vector<double>> sample(double time, std::int64_t step, SlabWorker& w);
  bool empty() const { return probes_.empty(); }

 private:
  const Case& case_;
  std::vector<ProbeSpec> probes_;
  std::vector<AppendFile> files_;
};

// Single probe evaluations on one slab (exposed for tests). NaN when this slab does not own the point.
double sample_pressure(SlabWorker& w, const Vec3d& at);
// Shepard-averaged fluid velocity (dim components), NaN components when not owned.
std::vector<double> sample_velocity(SlabWorker& w, const Vec3d& at);
double sample_height(SlabWorker& w, const Vec3d& gauge, const Case& c);
double local_front(SlabWorker& w, int axis);

}  // namespace spate
