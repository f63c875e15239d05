#pragma once
// Prescribed motions of walls (the tank or a solid): what the case says (MotionSpec, read by the
// case loader) and its evaluation in time (MotionSet), in double precision on the host. Each step
// the time loop hands the kernels the rigid-body state at the step's end and the rigid map from its
// start to its end (physics/wall_motion.hpp). Steering can scale a motion's amplitude or change a
// sinusoid's frequency while the run goes on: both take effect without a jump in position (the
// amplitude blends over one period, the phase is kept continuous), and every slab and every
// restart evaluates the same history.
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "../physics/params.hpp"

namespace spate {

using Vec3 = std::array<double, 3>;

// x(t) = centre + d(t) + R(theta(t)) (x(0) - centre), theta about `axis` (z in 2D).
struct MotionSpec {
  std::string body;        // "tank" or the solid's name
  // A sinusoid: d(t) = e(t) translation sin(omega t + phase), theta(t) = e(t) rotation sin(...),
  // e(t) the smooth ramp-up over `ramp` seconds (and ramp-down before `end`).
  Vec3 translation{0, 0, 0};  // amplitude per axis [m]
  double rotation = 0.0;      // amplitude [rad]
  double omega = 0.0;         // angular frequency [rad/s]
  double phase = 0.0;         // [rad]
  // Or a time series (`file`): times and displacement columns x, y, z [m] and angle [rad],
  // interpolated by natural cubic splines (continuous velocity and acceleration); before the
  // first time and after the last, the first and last values hold.
  std::string file;
  std::vector<double> times;
  std::vector<std::array<double, 4>> values;
  Vec3 axis{0, 0, 1};      // unit rotation axis
  Vec3 centre{0, 0, 0};    // the reference point at t = 0 (rotation centre)
  double ramp = 0.0;       // seconds of smooth start
  std::optional<double> end;  // the motion stops here (smoothly, over end_ramp seconds before it)
  double end_ramp = 0.0;
  double reach = 0.0;      // the largest distance of a point of the body from `centre` [m]
  // A floating solid (index into Case::bodies): the water moves it (sim/rigid_bodies.*); its
  // state each step comes from its dynamics, not from this spec, whose centre is its centre of mass.
  int floating = -1;
  bool sinusoid() const { return file.empty() && floating < 0; }
};

// The largest amplitude scale steering may set (the lattice leaves room for it).
constexpr double kMaxMotionAmplitudeScale = 2.0;

// A value and its first two time derivatives.
struct Jet {
  double v = 0.0, d = 0.0, dd = 0.0;
};

struct MotionSample {
  Vec3 displacement{0, 0, 0}, velocity{0, 0, 0}, acceleration{0, 0, 0};  // of the reference point
  double angle = 0.0, angular_velocity = 0.0, angular_acceleration = 0.0;
};

// Where the body's point x0 (at t = 0) is at the sample's time: x = centre + d + R(theta) (x0 -
// centre), R about the motion's unit axis (Rodrigues).
Vec3 moved_point(const MotionSpec& m, const MotionSample& s, const Vec3& x0);
// The inverse: where the body's point now at x was at t = 0.
Vec3 start_point(const MotionSpec& m, const MotionSample& s, const Vec3& x);
// A vector of the body's (a normal) turned as the body has turned: R(theta) v.
Vec3 turned(const MotionSpec& m, const MotionSample& s, const Vec3& v);
// The velocity of the body's point now at x: d' + theta' axis x (x - centre - d).
Vec3 point_velocity(const MotionSpec& m, const MotionSample& s, const Vec3& x);

class MotionSet {
 public:
  MotionSet() = default;
  MotionSet(std::vector<MotionSpec> specs, int dim);

  int size() const { return static_cast<int>(specs_.size()); }
  const MotionSpec& spec(int k) const { return specs_[k]; }
  MotionSample sample(int k, double t) const;
  // The largest displacement any point of the moving bodies can reach, per axis (with the largest
  // amplitude scale steering allows): the lattice's margin.
  Vec3 bound() const;

  // The kernels' view: the state at t1 and the rigid maps from t0 to t1 (t0 == t1: at rest).
  void set_step(PhysicsParams& P, double t0, double t1) const;

  // Steering (solver/sim/steering.*): the amplitude scale of motion k, blended from its present
  // value over one period from `time`; or a sinusoid's frequency [Hz] from `time`, the phase kept
  // continuous. check_* say why a change cannot be applied, or nothing.
  std::optional<std::string> check_amplitude(int k, double scale) const;
  std::optional<std::string> check_frequency(int k, double hertz) const;
  void set_amplitude(int k, double scale, double time);
  void set_frequency(int k, double hertz, double time);
  double frequency(int k) const;  // the current one [Hz] (0 for a time series)

 private:
  // From `start` on: the amplitude scale blends from scale_from to scale_to over [blend_start,
  // blend_start + blend]; the sinusoid runs at omega with phase.
  struct Segment {
    double start = 0.0;
    double scale_from = 1.0, scale_to = 1.0, blend_start = 0.0, blend = 0.0;
    double omega = 0.0, phase = 0.0;
  };
  const Segment& segment(int k, double t) const;
  Jet envelope(int k, double t) const;
  int dim_ = 3;
  std::vector<MotionSpec> specs_;
  std::vector<std::vector<Segment>> segments_;
  // Time series: per motion, per column (x, y, z, angle), the values and the spline's second
  // derivatives at the samples.
  std::vector<std::array<std::vector<double>, 4>> columns_, moments_;
};

// Whether this build moves floating solids (Simbody found at configure time; sim/rigid_bodies.*).
bool body_support();

// Reads a motion time series: a CSV file with a header naming its columns, `time` [s] and any of
// `x`, `y`, `z` [m] (displacements) and `angle` [degrees]. Throws std::runtime_error naming the
// file and line.
void read_motion_csv(const std::string& path, MotionSpec& spec);

}  // namespace spate
