#pragma once
// A periodic flow driven at a given mean velocity (case key `drive`): the body force along each
// driven (periodic) axis is set after every step, as OpenFOAM's meanVelocityForce sets a pressure
// gradient, so that the fluid's mean velocity U (over its particles, summed exactly: the same on
// every slab for any split) approaches the target U* with the time constant tau:
//   dU/dt = f - D  (f: body force; D: the mean deceleration by the walls and solids),
//   D_n   = f_{n-1} - (U_n - U_{n-1}) / dt_{n-1}  (what the last step showed),
//   f_n   = D_n + (U* - U_n) / max(tau, dt_n).
// With D steady the error decays as (1 - dt/tau) per step; tau = 0 corrects it in one step. At a
// steady state f is the mean pressure gradient over rho that holds the flow: the drag of every
// wall and solid divided by the fluid's mass (docs/physics.md, "Driven periodic flow").
#include <array>
#include <string>

#include "../case/case.hpp"
#include "../physics/params.hpp"

namespace spate {

class FlowDrive {
 public:
  explicit FlowDrive(const Case& c);
  bool on() const { return spec_.on; }
  // After step n of dt_taken (0 at the start of a run), with the mean velocity U_n now: sets
  // P.body_force along the driven axes for the next step of dt_next.
  void update(PhysicsParams& P, const std::array<double, 3>& mean_velocity, double dt_taken, double dt_next);
  // The body force now along each axis (driven or not) [m/s^2].
  const std::array<double, 3>& force() const { return force_; }
  // The state a restart continues from (checkpoint attribute `drive`): the force and the last
  // mean velocity, as hex floats; empty without a drive. restore() refuses a text that does not fit.
  std::string save() const;
  void restore(const std::string& text);
  // Puts the saved force into P (before the first rates of a restart).
  void apply(PhysicsParams& P) const;

 private:
  Case::DriveSpec spec_;
  int dim_;
  std::array<double, 3> force_{0, 0, 0};
  std::array<double, 3> last_mean_{0, 0, 0};
  bool has_last_ = false;  // false before the first update (no D to estimate yet)
};

}  // namespace spate
