#include "rigid_bodies.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>

#include "multibody.hpp"

namespace spate {

struct RigidBodies::Impl {
  std::unique_ptr<MotionSet> own_motions;  // the case's, unsteered, when the caller gives none
  std::unique_ptr<multibody::System> system;
};

namespace {

// The contact spheres' radius, in dp.
constexpr double kContactRadius = 0.01;

// A surface's signed distance (negative inside) and outward normal at a point, world frame at t = 0.
using StartDistance = std::function<double(const Vec3d& x, Vec3d& normal)>;

StartDistance shape_distance(ShapePtr shape, double sign) {
  return [shape, sign](const Vec3d& x, Vec3d& normal) {
    double n[3] = {0, 0, 0};
    const double d = shape->distance(x.data(), n);
    normal = {sign * n[0], sign * n[1], sign * n[2]};
    return sign * d;
  };
}

// A body's own surface in its frame (from its centre of mass at t = 0, world axes).
multibody::Distance body_surface(ShapePtr shape, const Vec3d& centre) {
  const StartDistance at = shape_distance(shape, 1.0);
  return [at, centre](const std::array<double, 3>& x, std::array<double, 3>& normal) {
    return at({x[0] + centre[0], x[1] + centre[1], x[2] + centre[2]}, normal);
  };
}

// An obstacle from its surface at t = 0, fixed (motion < 0) or moved by a prescribed motion: the
// point is taken back to where the surface was at t = 0, and the normal turned as it has turned.
// Its box: the surface's (lo, hi), widened by how far any motion can take it.
multibody::ObstacleInput obstacle(StartDistance at, Vec3d lo, Vec3d hi, const MotionSet& motions, int motion, int dim) {
  multibody::ObstacleInput o;
  constexpr double kFar = 1e300;
  const Vec3d reach = motion >= 0 ? motions.bound() : Vec3d{0, 0, 0};
  for (int k = 0; k < 3; ++k) {
    o.lo[k] = k < dim ? lo[k] - reach[k] : -kFar;
    o.hi[k] = k < dim ? hi[k] + reach[k] : kFar;
  }
  if (motion < 0) {
    o.distance = [at](double, const std::array<double, 3>& x, std::array<double, 3>& normal, std::array<double, 3>& velocity) {
      velocity = {0, 0, 0};
      return at(x, normal);
    };
    return o;
  }
  const MotionSet* set = &motions;
  o.distance = [at, set, motion, dim](double t, const std::array<double, 3>& x, std::array<double, 3>& normal, std::array<double, 3>& velocity) {
    const MotionSpec& m = set->spec(motion);
    const MotionSample s = set->sample(motion, t);
    Vec3d n0{0, 0, 0};
    const double d = at(start_point(m, s, x), n0);
    normal = turned(m, s, n0);
    velocity = point_velocity(m, s, x);
    for (int k = dim; k < 3; ++k) normal[k] = velocity[k] = 0.0;
    return d;
  };
  return o;
}

// Where a solid's corner x0 (at t = 0) is at time t and how fast it moves: fixed, or moved by its
// prescribed motion.
std::function<void(double, const std::array<double, 3>&, std::array<double, 3>&, std::array<double, 3>&)> corner_placement(
    const MotionSet& motions, int motion, int dim) {
  if (motion < 0)
    return [](double, const std::array<double, 3>& x0, std::array<double, 3>& x, std::array<double, 3>& velocity) {
      x = x0;
      velocity = {0, 0, 0};
    };
  const MotionSet* set = &motions;
  return [set, motion, dim](double t, const std::array<double, 3>& x0, std::array<double, 3>& x, std::array<double, 3>& velocity) {
    const MotionSpec& m = set->spec(motion);
    const MotionSample s = set->sample(motion, t);
    x = moved_point(m, s, x0);
    velocity = point_velocity(m, s, x);
    for (int k = dim; k < 3; ++k) x[k] = x0[k], velocity[k] = 0.0;
  };
}

// What a body with contact meets besides the other bodies: the tank's plane walls (none along a
// periodic axis nor at the open top; each the half-space behind its plane, whose normal points
// into the fluid) or a shaped tank's outside (everything but the vessel's inside), and every solid
// that does not float, each fixed or moved by its prescribed motion as the water's walls are.
std::vector<multibody::ObstacleInput> obstacles(const Case& c, const MotionSet& motions) {
  std::vector<multibody::ObstacleInput> out;
  constexpr double kFar = 1e300;
  const Vec3d everywhere_lo{-kFar, -kFar, -kFar}, everywhere_hi{kFar, kFar, kFar};
  if (c.tank_shape) out.push_back(obstacle(shape_distance(c.tank_shape, -1.0), everywhere_lo, everywhere_hi, motions, c.tank_motion, c.dim));
  const Vec3d hi = particle_tank_max(c);
  for (int face = 0; face < 2 * c.dim && !c.tank_shape; ++face) {
    if (tank_wall_missing(c, face)) continue;
    const int axis = face / 2;
    const double plane = face % 2 ? hi[axis] : c.tank_origin[axis], sign = face % 2 ? -1.0 : 1.0;
    const StartDistance wall = [axis, plane, sign](const Vec3d& x, Vec3d& normal) {
      normal = {0, 0, 0};
      normal[axis] = sign;
      return sign * (x[axis] - plane);
    };
    out.push_back(obstacle(wall, everywhere_lo, everywhere_hi, motions, c.tank_motion, c.dim));
  }
  for (const SolidSpec& s : c.solids) {
    if (s.motion >= 0 && c.motions[s.motion].floating >= 0) continue;
    const ShapePtr shape = solid_surface(s, c.dim);
    multibody::ObstacleInput o = obstacle(shape_distance(shape, 1.0), shape->lo, shape->hi, motions, s.motion, c.dim);
    for (const Vec3d& p : solid_corners(s, c.dim)) o.corners.push_back(p);
    o.place = corner_placement(motions, s.motion, c.dim);
    o.solid = true;
    out.push_back(std::move(o));
  }
  return out;
}

}  // namespace

RigidBodies::RigidBodies(const Case& c, const MotionSet* motions) : case_(c) {
  slots_.assign(c.bodies.size(), -1);
  for (std::size_t k = 0; k < c.motions.size(); ++k)
    if (c.motions[k].floating >= 0) slots_[c.motions[k].floating] = static_cast<int>(k);
  for (const BodySpec& b : c.bodies) {
    hinges_.push_back({b.hinge.stiffness, b.hinge.damping});
    for (const BodySpec::Spring& s : b.springs) springs_.push_back({s.stiffness, s.damping});
  }
  if (c.bodies.empty()) return;
  std::vector<multibody::BodyInput> in;
  for (const BodySpec& b : c.bodies) {
    multibody::BodyInput body{b.mass, b.centre_of_mass, b.inertia, b.free, {}, {}, {}};
    body.hinge = {b.hinge.on, b.hinge.point, b.hinge.axis, b.hinge.stiffness, b.hinge.damping};
    for (const BodySpec::Spring& s : b.springs) body.springs.push_back({s.point, s.anchor, s.stiffness, s.damping, s.length, s.slack, s.to});
    if (b.contact.on) {
      // Hertz: f = 4/3 E sqrt(R) x^1.5 carries the body's weight (at 9.81 m/s2 without gravity) on
      // one sphere at x = penetration. The spheres are small (dp/100): the body stands that far off
      // a wall it rests on.
      multibody::ContactInput& k = body.contact;
      k.on = true;
      k.radius = kContactRadius * c.dp;
      const double g = std::sqrt(c.gravity[0] * c.gravity[0] + c.gravity[1] * c.gravity[1] + c.gravity[2] * c.gravity[2]);
      const double weight = b.mass * (g > 0 ? g : 9.81);
      k.stiffness = 3.0 * weight / (4.0 * std::sqrt(k.radius) * std::pow(b.contact.penetration, 1.5));
      k.dissipation = b.contact.dissipation;
      k.friction = b.contact.friction;
      k.weight = weight;
      k.points = b.contact.points;
      k.edges = b.contact.edges;
      // Its surface in its own frame (from the centre of mass, world axes at t = 0).
      const SolidSpec& solid = c.solids[b.solid];
      k.surface = body_surface(solid_surface(solid, c.dim), b.centre_of_mass);
      for (const Vec3d& p : b.contact.points) k.reach = std::max(k.reach, std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]));
    }
    in.push_back(body);
  }
  impl_.reset(new Impl);
  if (!motions) impl_->own_motions.reset(new MotionSet(c.motions, c.dim)), motions = impl_->own_motions.get();
  impl_->system.reset(new multibody::System(c.dim, c.gravity, in, obstacles(c, *motions)));
  loads_.assign(c.bodies.size(), BodyLoad{});
  read_state();
  previous_ = states_;
}

RigidBodies::~RigidBodies() = default;

void RigidBodies::read_state() {
  states_.clear();
  for (const multibody::BodyOutput& o : impl_->system->state())
    states_.push_back({o.centre, o.velocity, o.angular_velocity, o.acceleration, o.angular_acceleration, o.rotation, o.angles});
}

void RigidBodies::apply_loads() {
  std::vector<multibody::Load> loads;
  for (const BodyLoad& l : loads_) loads.push_back({l.force[0], l.force[1], l.force[2], l.torque[0], l.torque[1], l.torque[2]});
  impl_->system->set_loads(loads);
  loaded_ = true;
  read_state();
}

void RigidBodies::set_loads(const std::vector<BodyLoad>& loads) {
  if (!impl_) return;
  loads_ = loads;
  apply_loads();
}

void RigidBodies::advance(double t0, double t1) {
  if (!impl_) return;
  previous_ = states_;
  impl_->system->advance(t0, t1);
  read_state();
}

namespace {

// The parts of a body's saved state, in order, each with its numbers.
constexpr const char* kStateParts[3] = {"q", "u", "load"};

}  // namespace

std::array<std::vector<double>, 3> RigidBodies::state_parts(int b) const {
  const BodyLoad& l = loads_[b];
  return {impl_->system->q(b), impl_->system->u(b), {l.force[0], l.force[1], l.force[2], l.torque[0], l.torque[1], l.torque[2]}};
}

std::string RigidBodies::save() const {
  std::string out;
  for (int b = 0; b < size(); ++b) {
    out += case_.solids[solid(b)].name;
    const auto parts = state_parts(b);
    for (int k = 0; k < 3; ++k) {
      out += std::string(" ") + kStateParts[k];
      for (double v : parts[k]) out += fmt::format(" {:a}", v);
    }
    out += "\n";
  }
  return out;
}

std::vector<std::pair<std::string, double>> RigidBodies::field_data() const {
  std::vector<std::pair<std::string, double>> out;
  for (int b = 0; b < size(); ++b) {
    const auto parts = state_parts(b);
    for (int k = 0; k < 3; ++k)
      for (std::size_t i = 0; i < parts[k].size(); ++i) out.emplace_back(fmt::format("floating_{}_{}{}", b, kStateParts[k], i), parts[k][i]);
  }
  return out;
}

std::string RigidBodies::text_from(const Case& c, const std::vector<std::pair<std::string, double>>& field_data) {
  std::string out;
  for (std::size_t b = 0; b < c.bodies.size(); ++b) {
    const std::string name = c.solids[c.bodies[b].solid].name;
    std::string line = name;
    for (const char* tag : kStateParts) {
      line += std::string(" ") + tag;
      const std::string prefix = fmt::format("floating_{}_{}", b, tag);
      for (const auto& [key, value] : field_data)
        if (key.rfind(prefix, 0) == 0 && key.find_first_not_of("0123456789", prefix.size()) == std::string::npos)
          line += fmt::format(" {:a}", value);
    }
    if (line == name + " q u load") return {};  // none of this body's numbers
    out += line + "\n";
  }
  return out;
}

void RigidBodies::restore(const std::string& text) {
  if (!impl_) {
    if (!text.empty()) throw std::runtime_error("it holds floating solids' states, and the case has none");
    return;
  }
  std::istringstream in(text);
  std::string line;
  for (int b = 0; b < size(); ++b) {
    const std::string name = case_.solids[solid(b)].name;
    if (!std::getline(in, line)) throw std::runtime_error(fmt::format("it has no state for floating solid '{}'", name));
    std::istringstream words(line);
    std::string word;
    words >> word;
    if (word != name) throw std::runtime_error(fmt::format("line {} is the state of '{}', expected floating solid '{}'", b + 1, word, name));
    // The numbers after `tag`, up to the next tag or the line's end.
    std::vector<std::pair<std::string, std::vector<double>>> parts;
    while (words >> word) {
      if (word == "q" || word == "u" || word == "load") {
        parts.push_back({word, {}});
        continue;
      }
      char* end = nullptr;
      const double x = std::strtod(word.c_str(), &end);
      if (parts.empty() || *end != '\0' || !std::isfinite(x))
        throw std::runtime_error(fmt::format("floating solid '{}': '{}' is not a finite number after q, u or load", name, word));
      parts.back().second.push_back(x);
    }
    if (parts.size() != 3 || parts[0].first != "q" || parts[1].first != "u" || parts[2].first != "load" || parts[2].second.size() != 6 ||
        !impl_->system->set(b, parts[0].second, parts[1].second))
      throw std::runtime_error(fmt::format("floating solid '{}': expected 'q' and 'u' with this body's coordinates and speeds, "
                                           "then 'load' with 6 numbers", name));
    for (int k = 0; k < 3; ++k) loads_[b].force[k] = parts[2].second[k], loads_[b].torque[k] = parts[2].second[3 + k];
  }
  if (std::getline(in, line) && !line.empty()) throw std::runtime_error("it holds more floating solids than the case");
  apply_loads();
  previous_ = states_;
}

void RigidBodies::set_spring(int line, const Coefficients& k) {
  springs_[line] = k;
  impl_->system->set_spring(line, k.stiffness, k.damping);
}

void RigidBodies::set_hinge(int b, const Coefficients& k) {
  hinges_[b] = k;
  impl_->system->set_hinge(b, k.stiffness, k.damping);
}

void RigidBodies::set_step(PhysicsParams& P) const {
  for (int b = 0; b < size(); ++b) {
    const BodyState &now = states_[b], &before = previous_[b];
    MotionState& m = P.motion[slots_[b]];
    MotionStep& step = P.motion_step[slots_[b]];
    for (int c = 0; c < 3; ++c) {
      m.velocity[c] = static_cast<float>(now.velocity[c]);
      m.angular_velocity[c] = static_cast<float>(now.angular_velocity[c]);
      m.centre[c] = static_cast<float>(now.centre[c]);
      m.acceleration[c] = loaded_ ? static_cast<float>(now.acceleration[c]) : 0.0f;
      m.angular_acceleration[c] = loaded_ ? static_cast<float>(now.angular_acceleration[c]) : 0.0f;
      step.from[c] = before.centre[c];
      step.to[c] = now.centre[c];
    }
    // R(t1) R(t0)^T: the turn over the step.
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        double v = 0.0;
        for (int k = 0; k < 3; ++k) v += now.rotation[i][k] * before.rotation[j][k];
        step.rotation[i][j] = v;
      }
  }
}

}  // namespace spate
