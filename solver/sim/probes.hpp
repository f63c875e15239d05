#pragma once
// Probes written as CSV time series (probes/<name>.csv): pressure at a point (Shepard average of the
// fluid, or of one phase), wall pressure on a sensor disc, water height at a gauge, pressure force
// on a named solid or one of its faces, surge-front position, centroid and mean velocity of a
// phase; interface of one fluid with the others. Sampling is collective; every value is independent
// of the split (owner-computed or exact), except that a kernel-weighted probe within a support of
// a slab face sums ghosts at the step's predicted positions (positions are not refreshed:
// docs/cases.md, "probes"). What each probe measures: docs/cases.md, "probes".
// The same code samples a run's saved snapshots and checkpoints afterwards (spate post).
//
// CSV format (docs/cases.md, scripts parse it): a header line `time[s],step,<column>[<unit>],...`,
// then one row per sample; the first column is the simulated time in seconds.
#include <cstdint>
#include <deque>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "../case/case.hpp"
#include "../io/output_file.hpp"
#include "rigid_bodies.hpp"
#include "slab_worker.hpp"

namespace spate {

// The trailing moving average of a sampled signal over a window of time, as the (piecewise-linear)
// signal's mean over [t - window, t]; while fewer than `window` seconds have been sampled, the mean
// over what has been. A sensor averaging over its window this way reports a peak about half a
// window late and lower than the instantaneous one, like a laboratory sensor sampled or filtered
// at that rate.
class MovingAverage {
 public:
  explicit MovingAverage(double window = 0.0) : window_(window) {}
  // Adds the sample (t, v) (t after every earlier sample) and returns the mean up to t.
  double add(double t, double v);

 private:
  double window_;
  std::deque<std::pair<double, double>> samples_;
};

class ProbeSet {
 public:
  // `writer`: this slab writes the files. `resume_step`: continue existing files after a restart
  // from that step (their rows of later steps, written by the run that went on past the
  // checkpoint, are dropped); none: start them afresh.
  ProbeSet(const Case& c, const std::filesystem::path& out_dir, bool writer, std::optional<std::int64_t> resume_step);
  // Collective over all slabs. Returns the sampled row values in probe order (for tests).
  // `motions`: where probes that follow a moving body are at `time` (none: they stay put);
  // `bodies`: the floating solids, for body probes (none: their rows are NaN).
  std::vector<std::vector<double>> sample(double time, std::int64_t step, SlabWorker& w, const MotionSet* motions = nullptr,
                                          const RigidBodies* bodies = nullptr);
  bool empty() const { return probes_.empty(); }

 private:
  struct Probe {
    ProbeSpec spec;
    std::vector<Vec3d> points;  // wall_pressure: where the disc samples the fluid
    MovingAverage average;      // wall_pressure with a window
  };
  const Case& case_;
  std::vector<Probe> probes_;
  std::vector<AppendFile> files_;
};

// The fluid's pressure load on each floating solid now: force and torque about its centre of mass,
// summed in particle id order (the same on every slab, for any split). Collective over all slabs.
std::vector<BodyLoad> body_loads(SlabWorker& w, const RigidBodies& bodies);

// The probe's value columns with their units, as in its CSV header ("pressure[Pa]", "vx[m/s]", ...).
std::vector<std::string> probe_columns(const ProbeSpec& p, int dim);
// The CSV header line of a probe, without the line break: "time[s],step,pressure[Pa]".
std::string probe_header(const ProbeSpec& p, int dim);
// What and where, for plot titles: "pressure at (0.89, 0.305, 0.02) m", "force on solid 'column'".
std::string probe_description(const ProbeSpec& p, int dim);

// Single probe evaluations on one slab (exposed for tests). NaN when this slab does not own the
// point. `phase`: only that fluid's particles count (-1: every fluid).
double sample_pressure(SlabWorker& w, const Vec3d& at, int phase = -1);
// Shepard-averaged fluid temperature [K] (heat transfer), NaN when not owned.
double sample_temperature(SlabWorker& w, const Vec3d& at, int phase = -1);
// Shepard-averaged fluid velocity (dim components), NaN components when not owned.
std::vector<double> sample_velocity(SlabWorker& w, const Vec3d& at, int phase = -1);
// Water height above the tank floor at a gauge (the probe's position, `connected` and `phase`);
// `floor`: where the floor is under a gauge that moves with the tank (default: the tank's floor).
double sample_height(SlabWorker& w, const ProbeSpec& gauge, const Case& c, std::optional<double> floor = std::nullopt);
// Where a probe that follows motion `gauge.follow` is at `time`: its point (for a height gauge, its
// point on the floor, vertical coordinate included) carried by the body's rigid motion.
Vec3d followed_position(const ProbeSpec& gauge, const Case& c, const MotionSet& motions, double time);
// Collective: the centroid (dim coordinates) and mean velocity (dim components) of the particles of
// fluid `phase` on all slabs (equal masses within a phase); NaN when it has none.
std::vector<double> sample_centroid(SlabWorker& w, int phase);
// Interface probe: where the volume fraction of fluid `phase` among all fluids (Shepard weights)
// crosses 1/2, on vertical lines every dp/2 across the tank (every dp along both horizontal axes in
// 3D), sampled every dp/4 up each line where fluid is (weight sum >= 1/2) and placed by linear
// interpolation between the two samples around a crossing, so that it resolves an interface
// displaced by a fraction of dp. The lowest and highest crossing on this slab's lines
// ({+inf, -inf} when none).
std::pair<double, double> local_interface_extent(SlabWorker& w, const Case& c, int phase);
// Furthest particle of fluid `phase` (-1: any fluid) along `axis` whose vertical coordinate is at
// least `lowest`; -infinity when there is none on this slab.
double local_front(SlabWorker& w, int axis, double lowest = -std::numeric_limits<double>::infinity(), int phase = -1);
// A front probe's `lowest`: a particle stands for water from its centre - dp/2 to centre + dp/2, so
// water at least min_depth deep has a particle centre at floor + min_depth - dp/2 or above
// (-infinity for min_depth 0: every fluid particle).
double front_level(const ProbeSpec& front, const Case& c);
// Where a wall-pressure sensor samples the fluid: points on its disc (in 2D a segment of length
// `diameter` along the face) on a square lattice of spacing at most dp/4, the centre alone for a
// point sensor; the same order on every slab.
std::vector<Vec3d> sensor_points(const ProbeSpec& sensor, int dim, double dp);
// The wall pressure at each of `points` that this slab owns (NaN at the others): the Adami pressure
// the fluid within reach implies at that point of the wall (physics/wall_boundary.hpp), not clipped;
// 0 where no fluid is within reach (a dry part of the sensor).
std::vector<double> sample_wall_pressure(SlabWorker& w, const std::vector<Vec3d>& points);

}  // namespace spate
