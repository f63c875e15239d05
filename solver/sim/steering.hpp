#pragma once
// Steering: named parameters a user may change while the solver runs (live from ParaView, or
// replayed from a log). Every change is validated here; accepted changes take effect at a step
// boundary, identically on every device and rank, and are recorded with step and time in
// steering.log and in checkpoints, so that a replay or a restart continues with them.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "../case/motion.hpp"
#include "../physics/params.hpp"

namespace spate {

struct Case;
class RigidBodies;

struct SteeringParameter {
  std::string name;
  int components;         // 1 for scalars, 3 for the gravity vector
  double min, max;        // each component (or the vector's magnitude for gravity)
  std::string unit, doc;
};

// The documented set (docs/live.md): gravity, viscosity, phase_viscosity, artificial_viscosity,
// motion_amplitude, motion_frequency, face_temperature, face_heat_flux, spring_stiffness,
// spring_damping, hinge_stiffness, hinge_damping, insitu_every, write_checkpoint, stop.
const std::vector<SteeringParameter>& steering_parameters();

struct SteeringChange {
  std::int64_t step = 0;  // the change applies from the step after this one
  double time = 0.0;
  std::string name;
  std::vector<double> value;
};

// What the solver state looks like to steering (it reads and writes these).
struct SteeringTarget {
  PhysicsParams* params = nullptr;
  int* insitu_every = nullptr;
  MotionSet* motions = nullptr;  // the walls' motions (motion_amplitude, motion_frequency)
  RigidBodies* bodies = nullptr;  // the floating solids (spring_*, hinge_*)
  bool checkpoint_now = false;
  bool stop = false;
};

// Reason for rejection, or nothing when the change is acceptable. `motions`: the run's wall
// motions (a motion change names one of them); null: not known (a recorded log read before the
// run), only the ranges are checked. `known`: the case (phase_viscosity names one of its fluids,
// face_temperature and face_heat_flux one of its tank's walls, in a case with heat transfer,
// spring_* one of its floating solids' springs, hinge_* one of its hinged floating solids); null:
// not known, only the ranges are checked.
std::optional<std::string> validate(const SteeringChange& change, int dim, const MotionSet* motions = nullptr, const Case* known = nullptr);
void apply(const SteeringChange& change, SteeringTarget& target);

// One line per change: "<step> <time> <name> <v0> [<v1> <v2>]", '#' starts a comment.
std::string to_log_line(const SteeringChange& change);
// Throws std::runtime_error naming the file and line when a line cannot be read; given the case's
// dimension, also when a change is one that validate() rejects (a recorded log, or the history in
// a checkpoint, holds only accepted changes: anything else is damaged input).
std::vector<SteeringChange> parse_log(const std::string& text, const std::string& file, std::optional<int> dim = std::nullopt);
std::vector<SteeringChange> read_log(const std::string& path, int dim);

// Where steering requests come from. Polled by one thread per process at step boundaries; what it
// returns is shared with every slab before anyone applies it.
class SteeringSource {
 public:
  virtual ~SteeringSource() = default;
  // Requests made since the last poll, stamped with `step` and `time`.
  virtual std::vector<SteeringChange> poll(std::int64_t step, double time) = 0;
};

// Replays a recorded log: returns the changes recorded for exactly this step.
class SteeringReplay final : public SteeringSource {
 public:
  explicit SteeringReplay(std::vector<SteeringChange> log) : log_(std::move(log)) {}
  std::vector<SteeringChange> poll(std::int64_t step, double time) override;

 private:
  std::vector<SteeringChange> log_;
  std::size_t next_ = 0;
};

}  // namespace spate
