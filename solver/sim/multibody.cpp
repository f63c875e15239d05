#include "multibody.hpp"

#include <Simbody.h>

#include <algorithm>
#include <optional>
#include <stdexcept>

namespace spate::multibody {

class Springs;

// One Simbody system for all bodies: each hangs from the ground by a Planar (2D: rotation about z,
// translation in x and y) or a Free (3D) mobilizer whose frame on the ground sits at the body's
// centre of mass at t = 0 with world axes, so that its coordinates are the displacement and
// rotation since t = 0. A locked degree of freedom is a ConstantSpeed constraint at zero on the
// mobilizer's speed for it (Planar: u = (wz, vx, vy); Free: u = (w, v), world axes).
struct System::Impl {
  int dim = 3;
  SimTK::MultibodySystem system;
  SimTK::SimbodyMatterSubsystem matter{system};
  SimTK::GeneralForceSubsystem forces{system};
  SimTK::Force::DiscreteForces fluid{forces, matter};
  std::vector<SimTK::MobilizedBody> bodies;
  // A hinged body's rotational spring and damper (none for an unhinged one); the lines, owned by
  // their Force::Custom.
  std::vector<std::optional<SimTK::Force::MobilityLinearSpring>> hinge_springs;
  std::vector<std::optional<SimTK::Force::MobilityLinearDamper>> hinge_dampers;
  Springs* springs = nullptr;
  SimTK::State state;
  // One integrator for the run, initialised afresh from the state each step (so that a restart,
  // whose integrator is new, steps bit for bit as the run it continues); made at the first step.
  std::unique_ptr<SimTK::RungeKuttaMersonIntegrator> integrator;
};

namespace {

// The mobilizer speed of each degree of freedom x, y, z, rx, ry, rz (-1: the mobilizer has none).
constexpr int kPlanarSpeed[6] = {1, 2, -1, -1, -1, 0};
constexpr int kFreeSpeed[6] = {3, 4, 5, 0, 1, 2};

std::array<double, 3> array_of(const SimTK::Vec3& v) { return {v[0], v[1], v[2]}; }
SimTK::Vec3 vec_of(const std::array<double, 3>& a, int dim) { return SimTK::Vec3(a[0], a[1], dim == 2 ? 0.0 : a[2]); }

}  // namespace

// The springs and mooring lines of every body, one Simbody custom force: tension
// T = k (L - L0) + c dL/dt along the line from the body point to its anchor, none for a slack line
// that is not taut (nor one that would push).
class Springs : public SimTK::Force::Custom::Implementation {
 public:
  struct Line {
    SimTK::MobilizedBody body;
    SimTK::Vec3 point;   // on the body, from its origin (the centre of mass), body frame
    SimTK::MobilizedBody other;  // the anchor's body: the ground for a fixed anchor
    SimTK::Vec3 anchor;  // on it, body frame (the ground's: world)
    double stiffness, damping, length;
    bool slack;
  };
  explicit Springs(std::vector<Line> lines) : lines_(std::move(lines)) {}
  // A steered line: the force reads it at its next evaluation (every step starts a new integration
  // from a state whose time was set, so no cached force outlives the change).
  void set(int line, double stiffness, double damping) {
    lines_[line].stiffness = stiffness;
    lines_[line].damping = damping;
  }

  void calcForce(const SimTK::State& state, SimTK::Vector_<SimTK::SpatialVec>& body_forces, SimTK::Vector_<SimTK::Vec3>&,
                 SimTK::Vector&) const override {
    for (const Line& l : lines_) {
      double T = 0.0;
      SimTK::Vec3 e;
      if (!tension(state, l, T, e)) continue;
      l.body.applyForceToBodyPoint(state, l.point, T * e, body_forces);
      l.other.applyForceToBodyPoint(state, l.anchor, -T * e, body_forces);  // the ground takes it unmoved
    }
  }
  SimTK::Real calcPotentialEnergy(const SimTK::State& state) const override {
    double energy = 0.0;
    for (const Line& l : lines_) {
      const double stretch = (ends(state, l).first).norm() - l.length;
      if (!l.slack || stretch > 0) energy += 0.5 * l.stiffness * stretch * stretch;
    }
    return energy;
  }
  bool dependsOnlyOnPositions() const override { return false; }

 private:
  // The line from the body point to the anchor, and its rate of change.
  static std::pair<SimTK::Vec3, SimTK::Vec3> ends(const SimTK::State& state, const Line& l) {
    return {l.other.findStationLocationInGround(state, l.anchor) - l.body.findStationLocationInGround(state, l.point),
            l.other.findStationVelocityInGround(state, l.anchor) - l.body.findStationVelocityInGround(state, l.point)};
  }
  // The line's tension and its unit direction from the body point to the anchor; false: no force.
  static bool tension(const SimTK::State& state, const Line& l, double& T, SimTK::Vec3& e) {
    const auto [d, v] = ends(state, l);
    const double L = d.norm();
    if (!(L > 0)) return false;
    e = d / L;
    const double rate = SimTK::dot(v, e);  // dL/dt
    T = l.stiffness * (L - l.length) + l.damping * rate;
    if (l.slack && (L <= l.length || T < 0)) return false;
    return true;
  }
  std::vector<Line> lines_;
};

// Contact of the bodies' spheres with the tank's plane walls, fixed obstacles (static solids, a
// shaped tank's outside) and the surfaces of the other bodies with contact, one Simbody custom
// force. Simbody's own contact (GeneralContactSubsystem with HuntCrossleyForce, which spate used
// for the walls until issue 32's contact between bodies) knows spheres and half-spaces, not
// spate's shapes (its triangle meshes need an elastic foundation finer than the particles), and its
// friction goes unstable in an impact (below); so the overlap here is each sphere against the
// other side's signed distance, and the force HuntCrossleyForce's law for a sphere of radius R
// sunk by x into a surface: f = 4/3 E sqrt(R) x^1.5 (1 + 3/2 c dx/dt) along the surface's normal,
// and Coulomb's mu f min(v_slip / v_t, 1) against the slip (HuntCrossleyForce.h, its static and
// dynamic coefficients equal, no viscous friction). A wall or obstacle is rigid: the contact takes
// the body's E, c and mu; two bodies combine theirs as Simbody combines two materials,
// E = (s1 E1^(2/3))^(3/2), s1 = E2^(2/3) / (E1^(2/3) + E2^(2/3)), c = c1 s1 + c2 (1 - s1),
// mu = 2 mu1 mu2 / (mu1 + mu2). Each pair of bodies is met both ways (the spheres of one against
// the other's surface, then the other's against the first's), so that a corner meets a face
// whichever body it belongs to; and the corners of the solids (ObstacleInput::corners) press on the
// bodies' faces the same way. In 3D a body's sharp edges carry spheres too, dp/2 apart, which meet
// the solids and the other bodies (an edge across an edge or a face), not the tank's walls (a
// body's corners are what meets a plane first). Summed in a fixed order (bodies, spheres; walls and obstacles, then bodies; then the
// solids' corners, bodies).
class ShapeContacts : public SimTK::Force::Custom::Implementation {
 public:
  struct Member {
    SimTK::MobilizedBody body;
    std::vector<SimTK::Vec3> points;  // body frame: the corners, then the edge spheres (3D)
    std::size_t corners;
    Distance surface;                 // body frame
    double reach, radius, stiffness, dissipation, friction, weight;
  };
  ShapeContacts(std::vector<Member> members, std::vector<ObstacleInput> obstacles, double transition)
      : members_(std::move(members)), obstacles_(std::move(obstacles)), transition_(transition) {
    // Simbody's combination of two materials (HuntCrossleyForce.h), once per pair of bodies.
    const std::size_t n = members_.size();
    pairs_.resize(n * n);
    for (std::size_t a = 0; a < n; ++a)
      for (std::size_t b = 0; b < n; ++b) {
        const Member &A = members_[a], &B = members_[b];
        const double e1 = std::pow(A.stiffness, 2.0 / 3.0), e2 = std::pow(B.stiffness, 2.0 / 3.0), s1 = e2 / (e1 + e2);
        pairs_[a * n + b] = {std::pow(s1 * e1, 1.5), A.dissipation * s1 + B.dissipation * (1 - s1),
                             2 * A.friction * B.friction / (A.friction + B.friction), std::min(A.weight, B.weight)};
      }
  }

  void calcForce(const SimTK::State& state, SimTK::Vector_<SimTK::SpatialVec>& body_forces, SimTK::Vector_<SimTK::Vec3>&,
                 SimTK::Vector&) const override {
    using SimTK::Vec3;
    const double t = state.getTime();
    for (std::size_t a = 0; a < members_.size(); ++a) {
      const Member& A = members_[a];
      const SimTK::Transform& X_GA = A.body.getBodyTransform(state);
      for (std::size_t k = 0; k < A.points.size(); ++k) {
        const Vec3& p = A.points[k];
        const Vec3 x = X_GA * p;
        const Vec3 v = A.body.findStationVelocityInGround(state, p);
        const bool edge = k >= A.corners;  // edge spheres meet solids and bodies, not the tank's walls
        for (const ObstacleInput& o : obstacles_) {
          if ((edge && !o.solid) || !near_box(x, o.lo, o.hi, A.radius)) continue;
          std::array<double, 3> n{}, u{};
          const double d = o.distance(t, {x[0], x[1], x[2]}, n, u);
          if (!(d < A.radius)) continue;
          const Vec3 f = force(A.radius - d, A.radius, Vec3(n[0], n[1], n[2]), v - Vec3(u[0], u[1], u[2]), A.stiffness, A.dissipation,
                               A.friction, A.weight);
          A.body.applyForceToBodyPoint(state, p, f, body_forces);
        }
        for (std::size_t b = 0; b < members_.size(); ++b) {
          const Member& B = members_[b];
          if (b == a) continue;
          const SimTK::Transform& X_GB = B.body.getBodyTransform(state);
          if ((x - X_GB.p()).norm() > B.reach + A.radius) continue;
          const Vec3 q = ~X_GB * x;  // the sphere's centre in B's frame
          std::array<double, 3> n{};
          const double d = B.surface({q[0], q[1], q[2]}, n);
          if (!(d < A.radius)) continue;
          const Pair& m = pairs_[a * members_.size() + b];
          const Vec3 f = force(A.radius - d, A.radius, X_GB.R() * Vec3(n[0], n[1], n[2]), v - B.body.findStationVelocityInGround(state, q), m.stiffness,
                               m.dissipation, m.friction, m.weight);
          A.body.applyForceToBodyPoint(state, p, f, body_forces);
          B.body.applyForceToBodyPoint(state, q, -f, body_forces);
        }
      }
    }
    // The solids' corners against the bodies' surfaces: a sphere of the body's radius at each
    // corner, pressed with the body's material, so that a body resting across a solid's edge
    // rests on it (its own corners are beyond the edge).
    for (const ObstacleInput& o : obstacles_) {
      for (const auto& c0 : o.corners) {
        std::array<double, 3> c{}, u{};
        o.place(t, c0, c, u);
        const Vec3 x(c[0], c[1], c[2]);
        for (const Member& B : members_) {
          const SimTK::Transform& X_GB = B.body.getBodyTransform(state);
          if ((x - X_GB.p()).norm() > B.reach + B.radius) continue;
          const Vec3 q = ~X_GB * x;
          std::array<double, 3> n{};
          const double d = B.surface({q[0], q[1], q[2]}, n);
          if (!(d < B.radius)) continue;
          const Vec3 f = force(B.radius - d, B.radius, X_GB.R() * Vec3(n[0], n[1], n[2]),
                               Vec3(u[0], u[1], u[2]) - B.body.findStationVelocityInGround(state, q), B.stiffness, B.dissipation, B.friction,
                               B.weight);
          B.body.applyForceToBodyPoint(state, q, -f, body_forces);
        }
      }
    }
  }
  SimTK::Real calcPotentialEnergy(const SimTK::State&) const override { return 0.0; }
  bool dependsOnlyOnPositions() const override { return false; }

 private:
  static bool near_box(const SimTK::Vec3& x, const std::array<double, 3>& lo, const std::array<double, 3>& hi, double margin) {
    for (int k = 0; k < 3; ++k)
      if (x[k] < lo[k] - margin || x[k] > hi[k] + margin) return false;
    return true;
  }
  // The force on a sphere of radius R sunk by `depth` into a surface whose outward normal is n, at
  // velocity v relative to the surface. Friction grows with the slip up to Coulomb's mu f at the
  // transition velocity times f / W (W the lighter body's weight; at least the transition velocity
  // itself): its slope, mu f / v_t, would otherwise grow with the normal force, and in an impact
  // (f some hundred times the weight) its rate, slope over mass, goes far past what the explicit
  // Runge-Kutta step can hold: a box landing on another began to rock from rounding and tumbled.
  // Held at mu W / v_t, the rate is that of a resting body (docs/physics.md, "Contact").
  SimTK::Vec3 force(double depth, double R, const SimTK::Vec3& n, const SimTK::Vec3& v, double E, double c, double mu, double W) const {
    if (!(depth > 0)) return SimTK::Vec3(0);
    const double rate = -SimTK::dot(v, n);  // dx/dt
    const double fn = 4.0 / 3.0 * E * std::sqrt(R) * std::pow(depth, 1.5) * (1 + 1.5 * c * rate);
    if (!(fn > 0)) return SimTK::Vec3(0);
    const SimTK::Vec3 slip = v - SimTK::dot(v, n) * n;
    const double vs = slip.norm();
    SimTK::Vec3 f = fn * n;
    const double transition = transition_ * std::max(1.0, fn / W);
    if (vs > 0) f -= (fn * mu * std::min(vs / transition, 1.0) / vs) * slip;
    return f;
  }
  // Two bodies' combined material; weight: the lighter one's.
  struct Pair {
    double stiffness, dissipation, friction, weight;
  };
  std::vector<Member> members_;
  std::vector<ObstacleInput> obstacles_;
  double transition_;
  std::vector<Pair> pairs_;  // [a * members + b]
};

namespace {

// Friction grows linearly with the slip speed up to mu N at this speed: a body held by friction
// creeps below it. Its rate mu g / vt (2,000-5,000 1/s) times the step stays inside the explicit
// Runge-Kutta's stability for steps up to about 5e-4 s (SPH steps are some 1e-4 s).
constexpr double kTransitionVelocity = 2e-3;  // [m/s]

// Contact: the spheres of every body with contact against the obstacles and the other bodies
// (ShapeContacts). Nothing when no body has contact, or nothing to meet.
void add_contact(System::Impl& m, const std::vector<BodyInput>& bodies, const std::vector<ObstacleInput>& obstacles, int dim) {
  std::vector<ShapeContacts::Member> members;
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    const ContactInput& c = bodies[b].contact;
    if (!c.on || !(c.stiffness > 0)) continue;
    ShapeContacts::Member member{m.bodies[b], {}, c.points.size(), c.surface, c.reach, c.radius, c.stiffness, c.dissipation, c.friction, c.weight};
    for (const auto& p : c.points) member.points.push_back(vec_of(p, dim));
    for (const auto& p : c.edges) member.points.push_back(vec_of(p, dim));
    members.push_back(std::move(member));
  }
  if (members.empty() || (obstacles.empty() && members.size() < 2)) return;
  SimTK::Force::Custom(m.forces, new ShapeContacts(std::move(members), obstacles, kTransitionVelocity));  // which owns it
}

}  // namespace

System::System(int dim, const std::array<double, 3>& g, const std::vector<BodyInput>& bodies,
               const std::vector<ObstacleInput>& obstacles)
    : impl_(new Impl) {
  using namespace SimTK;
  Impl& m = *impl_;
  m.dim = dim;
  Force::UniformGravity(m.forces, m.matter, Vec3(g[0], g[1], dim == 2 ? 0.0 : g[2]));
  std::vector<Springs::Line> lines;
  for (const BodyInput& b : bodies) {
    const auto& I = b.inertia;
    // 2D: only Izz acts (Planar turns about z); the other moments just make a valid inertia.
    const Inertia inertia = dim == 2 ? Inertia(I[2], I[2], I[2]) : Inertia(I[0], I[1], I[2], I[3], I[4], I[5]);
    const Body::Rigid info(MassProperties(b.mass, Vec3(0), inertia));
    const Vec3 centre = vec_of(b.centre, dim);
    MobilizedBody mob;
    if (b.hinge.on) {
      // A Pin turns about the z axis of its frames: both sit at the hinge with z along its axis,
      // so that the body's frame is the world's at q = 0.
      const Rotation R = dim == 2 ? Rotation() : Rotation(UnitVec3(vec_of(b.hinge.axis, 3)), ZAxis);
      const Vec3 hinge = vec_of(b.hinge.point, dim);
      MobilizedBody::Pin pin(m.matter.Ground(), Transform(R, hinge), info, Transform(R, hinge - centre));
      // Both always, so that steering can give a hinge without them one.
      m.hinge_springs.emplace_back(Force::MobilityLinearSpring(m.forces, pin, MobilizerQIndex(0), b.hinge.stiffness, 0.0));
      m.hinge_dampers.emplace_back(Force::MobilityLinearDamper(m.forces, pin, MobilizerUIndex(0), b.hinge.damping));
      mob = pin;
    } else {
      m.hinge_springs.emplace_back();
      m.hinge_dampers.emplace_back();
      const Transform at(centre);
      mob = dim == 2 ? MobilizedBody(MobilizedBody::Planar(m.matter.Ground(), at, info, Transform()))
                     : MobilizedBody(MobilizedBody::Free(m.matter.Ground(), at, info, Transform()));
      for (int dof = 0; dof < 6; ++dof) {
        const int u = (dim == 2 ? kPlanarSpeed : kFreeSpeed)[dof];
        if (u >= 0 && !b.free[dof]) Constraint::ConstantSpeed(mob, MobilizerUIndex(u), 0.0);
      }
    }
    for (const SpringInput& s : b.springs) {
      const bool fixed = s.other < 0;
      const SimTK::MobilizedBody& other = fixed ? m.matter.Ground() : m.bodies[s.other];
      const Vec3 anchor = vec_of(s.anchor, dim) - (fixed ? Vec3(0) : vec_of(bodies[s.other].centre, dim));
      lines.push_back({mob, vec_of(s.point, dim) - centre, other, anchor, s.stiffness, s.damping, s.length, s.slack});
    }
    m.bodies.push_back(mob);
  }
  add_contact(m, bodies, obstacles, dim);
  if (!lines.empty()) {
    m.springs = new Springs(std::move(lines));
    Force::Custom(m.forces, m.springs);  // which owns it
  }
  m.state = m.system.realizeTopology();
  set_loads(std::vector<Load>(bodies.size(), Load{}));
}

System::~System() = default;

void System::set_loads(const std::vector<Load>& loads) {
  Impl& m = *impl_;
  for (std::size_t b = 0; b < m.bodies.size(); ++b) {
    const Load& l = loads[b];
    m.fluid.setOneBodyForce(m.state, m.bodies[b], SimTK::SpatialVec(SimTK::Vec3(l[3], l[4], l[5]), SimTK::Vec3(l[0], l[1], l[2])));
  }
  m.system.realize(m.state, SimTK::Stage::Acceleration);
}

void System::advance(double t0, double t1) {
  using namespace SimTK;
  Impl& m = *impl_;
  m.state.setTime(t0);
  // One fixed step of a 4th-order Runge-Kutta (Merson) from a fresh start: the result depends on
  // the state and the loads alone, so that a restart continues bit for bit.
  if (!m.integrator) {
    m.integrator.reset(new RungeKuttaMersonIntegrator(m.system));
    m.integrator->setConstraintTolerance(1e-12);
  }
  RungeKuttaMersonIntegrator& integrator = *m.integrator;
  integrator.setFixedStepSize(t1 - t0);
  integrator.initialize(m.state);
  // The first call after initialize() only reports the start of the interval (StartOfContinuousInterval).
  for (int calls = 0; calls < 8 && integrator.getTime() < t1; ++calls)
    if (integrator.stepTo(t1) == Integrator::ReachedReportTime) break;
  if (integrator.getTime() != t1) throw std::runtime_error("the floating solids' integrator did not reach the step's end");
  m.state = integrator.getState();
  m.system.realize(m.state, Stage::Acceleration);
}

std::vector<BodyOutput> System::state() const {
  const Impl& m = *impl_;
  std::vector<BodyOutput> out(m.bodies.size());
  for (std::size_t b = 0; b < m.bodies.size(); ++b) {
    const SimTK::MobilizedBody& mob = m.bodies[b];
    BodyOutput& s = out[b];
    s.centre = array_of(mob.getBodyOriginLocation(m.state));
    s.velocity = array_of(mob.getBodyOriginVelocity(m.state));
    s.angular_velocity = array_of(mob.getBodyAngularVelocity(m.state));
    s.acceleration = array_of(mob.getBodyOriginAcceleration(m.state));
    s.angular_acceleration = array_of(mob.getBodyAngularAcceleration(m.state));
    const SimTK::Rotation& R = mob.getBodyRotation(m.state);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) s.rotation[i][j] = R[i][j];
    s.angles = m.dim == 2 ? std::array<double, 3>{0.0, 0.0, mob.getOneQ(m.state, 0)} : array_of(R.convertRotationToBodyFixedXYZ());
  }
  return out;
}

std::vector<double> System::q(int b) const {
  const SimTK::Vector v = impl_->bodies[b].getQAsVector(impl_->state);
  return std::vector<double>(&v[0], &v[0] + v.size());
}

std::vector<double> System::u(int b) const {
  const SimTK::Vector v = impl_->bodies[b].getUAsVector(impl_->state);
  return std::vector<double>(&v[0], &v[0] + v.size());
}

bool System::set(int b, const std::vector<double>& q, const std::vector<double>& u) {
  Impl& m = *impl_;
  SimTK::MobilizedBody& mob = m.bodies[b];
  if (static_cast<int>(q.size()) != mob.getNumQ(m.state) || static_cast<int>(u.size()) != mob.getNumU(m.state)) return false;
  for (int k = 0; k < static_cast<int>(q.size()); ++k) mob.setOneQ(m.state, k, q[k]);
  for (int k = 0; k < static_cast<int>(u.size()); ++k) mob.setOneU(m.state, k, u[k]);
  return true;
}

void System::set_spring(int line, double stiffness, double damping) {
  if (impl_->springs) impl_->springs->set(line, stiffness, damping);
}

void System::set_hinge(int b, double stiffness, double damping) {
  Impl& m = *impl_;
  if (!m.hinge_springs[b]) return;
  m.hinge_springs[b]->setStiffness(m.state, stiffness);
  m.hinge_dampers[b]->setDamping(m.state, damping);
}

}  // namespace spate::multibody
