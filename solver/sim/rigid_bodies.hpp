#pragma once
// Bodies the water moves (issue 32): the case's floating solids (Case::bodies) as rigid bodies of a
// Simbody multibody system (docs/design.md says why Simbody). Each step of the time loop:
//   1. advance(t_n, t_n+1): the bodies move from t_n to t_n+1 under gravity, their constraints
//      (locked degrees of freedom) and the fluid's load measured at t_n (set_loads), held over
//      the step (explicit coupling, as the leading SPH codes do; docs/physics.md, "Floating solids");
//   2. set_step(P): the kernels see each body as a moving wall, through its motion slot: the rigid
//      map of its particles from t_n to t_n+1 and its velocity and acceleration at t_n+1;
//   3. the SPH step; then set_loads(the fluid's load at t_n+1; sim/probes.hpp, body_loads).
// Every slab holds its own copy and gets the same loads (summed in particle id order), so every
// copy computes the same motion, bit for bit, however the domain is split. Simbody itself stays
// behind sim/multibody.hpp; without it in the build the case loader refuses floating solids
// (body_support()).
#include <array>
#include <memory>
#include <string>
#include <vector>

#include "../case/case.hpp"
#include "../case/motion.hpp"
#include "../physics/params.hpp"

namespace spate {

// The fluid's load on a body: the force and the torque about its centre of mass, world axes [N,
// N m] (2D: per metre of depth).
struct BodyLoad {
  std::array<double, 3> force{0, 0, 0}, torque{0, 0, 0};
};

// A body's state at the present time, world frame.
struct BodyState {
  std::array<double, 3> centre{0, 0, 0};    // centre of mass [m]
  std::array<double, 3> velocity{0, 0, 0};  // of the centre of mass [m/s]
  std::array<double, 3> angular_velocity{0, 0, 0};  // [rad/s]
  std::array<double, 3> acceleration{0, 0, 0};      // [m/s2]
  std::array<double, 3> angular_acceleration{0, 0, 0};  // [rad/s2]
  std::array<std::array<double, 3>, 3> rotation{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};  // body to world since t = 0
  std::array<double, 3> angles{0, 0, 0};  // rad: 2D the rotation about z (not wrapped); 3D body-fixed x-y-z
};

class RigidBodies {
 public:
  // `motions`: the run's prescribed motions as steered (they move the walls and solids that bodies
  // meet through contact), kept by the caller for the bodies' life; none: the case's, unsteered.
  explicit RigidBodies(const Case& c, const MotionSet* motions = nullptr);
  ~RigidBodies();
  RigidBodies(const RigidBodies&) = delete;
  RigidBodies& operator=(const RigidBodies&) = delete;

  int size() const { return static_cast<int>(states_.size()); }
  bool empty() const { return states_.empty(); }
  // The motion slot (Case::motions) and the solid (Case::solids) of body b.
  int slot(int b) const { return slots_[b]; }
  int solid(int b) const { return case_.bodies[b].solid; }
  // The largest distance of a point of body b from its centre of mass [m].
  double reach(int b) const { return case_.motions[slots_[b]].reach; }

  // Advances every body from t0 to t1 with the last loads held over the step.
  void advance(double t0, double t1);
  // Writes each body's motion slot: the rigid map from before the last advance to now, and the
  // state now (the identity map before the first advance or after restore; no acceleration before
  // the first loads are known: the first rates see the body at rest).
  void set_step(PhysicsParams& P) const;

  const BodyState& state(int b) const { return states_[b]; }
  const BodyLoad& load(int b) const { return loads_[b]; }  // the last loads given (or restored)
  // The loads measured now (one per body): the bodies' accelerations now follow from them.
  void set_loads(const std::vector<BodyLoad>& loads);

  // The bodies' state and last loads as text (exact: hexadecimal floats), for checkpoints; restore
  // reads it back, throwing std::runtime_error (saying why) when it does not fit the case's bodies.
  std::string save() const;
  void restore(const std::string& text);
  // The same state as named numbers for a snapshot's field data (floating_<b>_q<i>, _u<i>,
  // _load<i>), and its text for restore() again from a snapshot's field data (empty when it has
  // none: a snapshot written before them).
  std::vector<std::pair<std::string, double>> field_data() const;
  static std::string text_from(const Case& c, const std::vector<std::pair<std::string, double>>& field_data);

  // Steering (sim/steering.hpp): a spring or mooring line, numbered over the floating solids in
  // order and each one's lines in order, or a hinged body's rotational spring and damper, takes a
  // new stiffness or damping from the next step on. The values now, first the case's.
  struct Coefficients {
    double stiffness = 0.0, damping = 0.0;
  };
  int spring_count() const { return static_cast<int>(springs_.size()); }
  const Coefficients& spring(int line) const { return springs_[line]; }
  void set_spring(int line, const Coefficients& k);
  const Coefficients& hinge(int b) const { return hinges_[b]; }
  void set_hinge(int b, const Coefficients& k);

 private:
  struct Impl;
  void read_state();
  void apply_loads();  // loads_ to the system: the accelerations now
  // Body b's saved state: its coordinates q, speeds u and last load (save(), field_data()).
  std::array<std::vector<double>, 3> state_parts(int b) const;
  const Case& case_;
  std::unique_ptr<Impl> impl_;
  std::vector<int> slots_;
  std::vector<Coefficients> springs_, hinges_;
  std::vector<BodyState> states_, previous_;
  std::vector<BodyLoad> loads_;
  bool loaded_ = false;  // loads have been set (or restored)
};

}  // namespace spate
