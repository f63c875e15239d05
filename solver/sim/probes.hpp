#pragma once
// Probes written as CSV time series (probes/<name>.csv): pressure at a point (Shepard average of the
// fluid, or of one phase), water height at a gauge, total pressure force on a named solid,
// surge-front position, centroid and mean velocity of a phase.
// Sampling is collective; every value is independent of the split (owner-computed or exact).
// The same code samples a run's saved snapshots and checkpoints afterwards (spate post).
//
// CSV format (docs/cases.md, scripts parse it): a header line `time[s],step,<column>[<unit>],...`,
// then one row per sample; the first column is the simulated time in seconds.
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "../case/case.hpp"
#include "slab_worker.hpp"

namespace spate {

class ProbeSet {
 public:
  // `writer`: this slab writes the files. `append`: continue existing files (restart).
  ProbeSet(const Case& c, const std::filesystem::path& out_dir, bool writer, bool append);
  // Collective over all slabs. Returns the sampled row values in probe order (for tests).
  std::vector<std::vector<double>> sample(double time, std::int64_t step, SlabWorker& w);
  bool empty() const { return probes_.empty(); }

 private:
  const Case& case_;
  std::vector<ProbeSpec> probes_;
  std::vector<std::unique_ptr<std::ofstream>> files_;
};

// The probe's value columns with their units, as in its CSV header ("pressure[Pa]", "vx[m/s]", ...).
std::vector<std::string> probe_columns(const ProbeSpec& p, int dim);
// The CSV header line of a probe, without the line break: "time[s],step,pressure[Pa]".
std::string probe_header(const ProbeSpec& p, int dim);
// What and where, for plot titles: "pressure at (0.89, 0.305, 0.02) m", "force on solid 'column'".
std::string probe_description(const ProbeSpec& p, int dim);

// Single probe evaluations on one slab (exposed for tests). NaN when this slab does not own the
// point. `phase`: only that fluid's particles count (-1: every fluid).
double sample_pressure(SlabWorker& w, const Vec3d& at, int phase = -1);
// Shepard-averaged fluid velocity (dim components), NaN components when not owned.
std::vector<double> sample_velocity(SlabWorker& w, const Vec3d& at, int phase = -1);
// Water height above the tank floor at a gauge (the probe's position, `connected` and `phase`).
double sample_height(SlabWorker& w, const ProbeSpec& gauge, const Case& c);
// Collective: the centroid (dim coordinates) and mean velocity (dim components) of the particles of
// fluid `phase` on all slabs (equal masses within a phase); NaN when it has none.
std::vector<double> sample_centroid(SlabWorker& w, int phase);
// Furthest fluid particle along `axis` whose vertical coordinate is at least `lowest`; -infinity
// when there is none on this slab.
double local_front(SlabWorker& w, int axis, double lowest = -std::numeric_limits<double>::infinity());
// A front probe's `lowest`: a particle stands for water from its centre - dp/2 to centre + dp/2, so
// water at least min_depth deep has a particle centre at floor + min_depth - dp/2 or above
// (-infinity for min_depth 0: every fluid particle).
double front_level(const ProbeSpec& front, const Case& c);

}  // namespace spate
