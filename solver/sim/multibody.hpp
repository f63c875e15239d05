#pragma once
// The multibody system behind the floating solids (sim/rigid_bodies.*): Simbody, behind an
// interface of plain types. Its translation unit is compiled as C++17: Simbody 3.7's headers do
// not compile as C++20 (their index types' operator== turns ambiguous under C++20's rewritten
// comparisons), so nothing of Simbody may reach a spate header.
#include <array>
#include <functional>
#include <memory>
#include <vector>

namespace spate::multibody {

// A hinge: the body turns about `axis` (2D: z) through `point` only, with a rotational spring and
// damper about its start angle.
struct HingeInput {
  bool on = false;
  std::array<double, 3> point{}, axis{0, 0, 1};
  double stiffness = 0.0, damping = 0.0;
};

// A spring or mooring line from a body point (at t = 0) to a fixed anchor (world), or to a point of
// another body (`other`, an earlier one; `anchor` its point at t = 0).
struct SpringInput {
  std::array<double, 3> point{}, anchor{};
  double stiffness = 0.0, damping = 0.0, length = 0.0;
  bool slack = false;  // pulls only, when longer than `length`
  int other = -1;
};

// A signed distance to a surface [m], negative inside, with the unit outward normal there.
using Distance = std::function<double(const std::array<double, 3>& x, std::array<double, 3>& normal)>;

// Contact (Hunt & Crossley's force on Hertz's law, ShapeContacts in multibody.cpp): small spheres
// centred at `points` (body frame: from the centre of mass, world axes at t = 0), the body's
// outermost points, pressed against the obstacles and the other bodies with contact, found by their
// signed distances.
struct ContactInput {
  bool on = false;
  std::vector<std::array<double, 3>> points;  // the spheres' centres, body frame
  std::vector<std::array<double, 3>> edges;   // more along its sharp edges (3D), for solids and bodies only
  Distance surface;    // the body's own surface, body frame (other bodies' spheres press on it)
  double reach = 0.0;  // the largest distance of a point of the body from its centre of mass [m]
  double radius = 0.0;       // of each sphere [m]
  double stiffness = 0.0;    // plane-strain modulus [Pa]: Hertz f = 4/3 E sqrt(R) x^1.5
  double dissipation = 0.0;  // Hunt & Crossley c [s/m]
  double friction = 0.0;     // Coulomb's coefficient against the walls
  double weight = 0.0;       // the body's weight [N] (m g): ShapeContacts' friction scale
};

// What bodies with contact meet besides each other (a tank's wall, a solid, a shaped tank's
// outside), fixed or moved by a prescribed motion: at time t, the signed distance of the world
// point x (negative where a body may not go), the unit outward normal and the surface's velocity
// there; and a box it stays inside at all times (a point outside it, farther than a contact
// sphere's radius, is not tested).
// A solid's corners (`corners`, world at t = 0: its convex hull's vertices) press on the bodies'
// faces as the bodies' own corners press on it (a body resting across a step's edge rests on the
// edge); `place` puts a corner where the solid has it at time t, with its velocity. None for the
// tank's walls.
struct ObstacleInput {
  std::function<double(double t, const std::array<double, 3>& x, std::array<double, 3>& normal, std::array<double, 3>& velocity)> distance;
  std::array<double, 3> lo{}, hi{};
  std::vector<std::array<double, 3>> corners;
  std::function<void(double t, const std::array<double, 3>& x0, std::array<double, 3>& x, std::array<double, 3>& velocity)> place;
  bool solid = false;  // a solid (the bodies' edge spheres meet it), not a tank wall
};

struct BodyInput {
  double mass = 0.0;              // [kg] (2D: per metre)
  std::array<double, 3> centre{};  // centre of mass at t = 0 [m]
  std::array<double, 6> inertia{};  // Ixx, Iyy, Izz, Ixy, Ixz, Iyz about it (2D: Izz acts)
  std::array<bool, 6> free{};      // x, y, z, rx, ry, rz (without a hinge)
  HingeInput hinge;
  std::vector<SpringInput> springs;
  ContactInput contact;
};

struct BodyOutput {
  std::array<double, 3> centre{}, velocity{}, angular_velocity{}, acceleration{}, angular_acceleration{};
  std::array<std::array<double, 3>, 3> rotation{};
  std::array<double, 3> angles{};  // 2D: (0, 0, the turn about z); 3D: body-fixed x-y-z [rad]
};

// Force (0..2) and torque about the centre of mass (3..5), world axes.
using Load = std::array<double, 6>;

class System {
 public:
  System(int dim, const std::array<double, 3>& gravity, const std::vector<BodyInput>& bodies,
         const std::vector<ObstacleInput>& obstacles = {});
  ~System();
  // The loads now: the accelerations follow.
  void set_loads(const std::vector<Load>& loads);
  // One fixed step from t0 to t1 with the loads held.
  void advance(double t0, double t1);
  std::vector<BodyOutput> state() const;
  // Body b's generalised coordinates and speeds (for checkpoints).
  std::vector<double> q(int b) const;
  std::vector<double> u(int b) const;
  // Returns false when their counts do not fit body b.
  bool set(int b, const std::vector<double>& q, const std::vector<double>& u);
  // Steering: spring or mooring line `line` (numbered over the bodies in order, each body's in its
  // order) takes a new stiffness or damping; hinged body b's rotational spring or damper too.
  // They act from the next step on.
  void set_spring(int line, double stiffness, double damping);
  void set_hinge(int b, double stiffness, double damping);

  struct Impl;  // Simbody's side (multibody.cpp), opaque here

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace spate::multibody
