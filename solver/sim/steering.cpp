#include "steering.hpp"

#include "../case/case.hpp"
#include "../io/input_file.hpp"
#include "rigid_bodies.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>

namespace spate {

const std::vector<SteeringParameter>& steering_parameters() {
  static const std::vector<SteeringParameter> p = {
      {"gravity", 3, 0.0, 100.0, "m/s2", "gravity vector (its magnitude at most 100 m/s2); tilt it to start sloshing"},
      {"viscosity", 1, 0.0, 10.0, "Pa s", "dynamic viscosity mu of eq. 8 (of the fluid, material 0)"},
      {"phase_viscosity", 2, 0.0, 10.0, "Pa s", "fluid number (the case's order, as spate info lists them), its dynamic viscosity mu"},
      {"artificial_viscosity", 1, 0.0, 1.0, "", "Monaghan alpha (0 switches it off)"},
      {"motion_amplitude", 2, 0.0, kMaxMotionAmplitudeScale, "",
       "motion number, amplitude scale (1: the case's amplitude; blends over one period, no jump)"},
      {"motion_frequency", 2, 0.0, 100.0, "Hz", "motion number, frequency of a sinusoidal motion (the phase stays continuous)"},
      {"face_temperature", 2, 0.0, 1.0e4, "K",
       "tank face number (0 x-, 1 x+, 2 y-, 3 y+, 4 z-, 5 z+), its fixed temperature (heat transfer; the face holds it from the next step)"},
      {"face_heat_flux", 2, -1.0e9, 1.0e9, "W/m2", "tank face number, the heat flux into the fluid through it (0: adiabatic)"},
      {"spring_stiffness", 2, 0.0, 1.0e9, "N/m",
       "spring number (the floating solids' springs and mooring lines in the case's order), its stiffness (2D: per metre)"},
      {"spring_damping", 2, 0.0, 1.0e9, "N s/m", "spring number, its damping (2D: per metre)"},
      {"hinge_stiffness", 2, 0.0, 1.0e9, "N m/rad",
       "floating solid number (the case's order, as spate info lists them), its hinge's rotational stiffness (2D: per metre)"},
      {"hinge_damping", 2, 0.0, 1.0e9, "N m s/rad", "floating solid number, its hinge's rotational damping (2D: per metre)"},
      {"insitu_every", 1, 1.0, 1.0e6, "steps", "steps between in-situ pipeline executions"},
      {"write_checkpoint", 1, 0.0, 1.0, "", "1: write a checkpoint at the next step boundary"},
      {"stop", 1, 0.0, 1.0, "", "1: write a checkpoint and stop cleanly (exit 0)"},
  };
  return p;
}

std::optional<std::string> validate(const SteeringChange& c, int dim, const MotionSet* motions, const Case* known) {
  const SteeringParameter* spec = nullptr;
  for (auto& p : steering_parameters())
    if (p.name == c.name) spec = &p;
  if (!spec) return "unknown parameter '" + c.name + "'";
  if (static_cast<int>(c.value.size()) != spec->components)
    return c.name + " takes " + std::to_string(spec->components) + " value(s), got " + std::to_string(c.value.size());
  for (double v : c.value)
    if (!std::isfinite(v)) return c.name + ": value is not finite";
  if (c.name == "gravity") {
    double m2 = 0;
    for (double v : c.value) m2 += v * v;
    if (std::sqrt(m2) > spec->max) return "gravity: magnitude " + std::to_string(std::sqrt(m2)) + " m/s2 exceeds 100";
    if (dim == 2 && c.value[2] != 0.0) return "gravity: a 2D case has no z component (third value must be 0)";
    return std::nullopt;
  }
  if (c.name == "motion_amplitude" || c.name == "motion_frequency") {
    const double k = c.value[0];
    if (k != std::floor(k) || k < 0) return c.name + ": the motion number must be a whole number >= 0";
    if (!motions) {
      // The case's motions are not known here (a recorded log read before the run, e.g. a
      // checkpoint's): only the ranges; the run checks the motion itself before applying it.
      const double v = c.value[1];
      if (v < spec->min || v > spec->max || (c.name == "motion_frequency" && !(v > 0)))
        return c.name + ": " + std::to_string(v) + " is outside the parameter's range";
      return std::nullopt;
    }
    if (motions->size() == 0) return c.name + ": the case has no moving walls";
    const auto why = c.name == "motion_amplitude" ? motions->check_amplitude(static_cast<int>(k), c.value[1])
                                                  : motions->check_frequency(static_cast<int>(k), c.value[1]);
    if (why) return c.name + ": " + *why;
    return std::nullopt;
  }
  if (c.name == "phase_viscosity") {
    const double k = c.value[0];
    if (k != std::floor(k) || k < 0) return "phase_viscosity: the fluid number must be a whole number >= 0";
    const int fluids = known ? static_cast<int>(known->fluids.size()) : 0;
    if (fluids > 0 && k >= fluids)
      return "phase_viscosity: the case has " + std::to_string(fluids) + " fluid(s), numbered from 0; there is no fluid " +
             std::to_string(static_cast<long long>(k));
    if (k >= kMaxFluids) return "phase_viscosity: there is no fluid " + std::to_string(static_cast<long long>(k));
  }
  if ((c.name == "viscosity" || c.name == "phase_viscosity") && known) {
    const auto k = static_cast<std::size_t>(c.name == "viscosity" ? 0.0 : c.value[0]);
    if (k < known->fluids.size() && !known->fluids[k].thermal.viscosity.empty())
      return c.name + ": fluid '" + known->fluids[k].name + "' follows its viscosity table (thermal.viscosity)";
  }
  if (c.name == "face_temperature" || c.name == "face_heat_flux") {
    const double f = c.value[0];
    if (f != std::floor(f) || f < 0 || f > 5) return c.name + ": the face number must be a whole number from 0 to 5 (x-, x+, y-, y+, z-, z+)";
    if (known) {
      if (!known->heat) return c.name + ": the case has no heat transfer (no heat: section)";
      if (auto why = tank_wall_missing(*known, static_cast<int>(f))) return c.name + ": face " + std::to_string(static_cast<int>(f)) + " " + *why;
    }
  }
  if (c.name.rfind("spring_", 0) == 0 || c.name.rfind("hinge_", 0) == 0) {
    const bool spring = c.name[0] == 's';
    const double k = c.value[0];
    if (k != std::floor(k) || k < 0) return c.name + ": the " + (spring ? "spring" : "floating solid") + " number must be a whole number >= 0";
    if (known) {
      int springs = 0;
      for (const BodySpec& b : known->bodies) springs += static_cast<int>(b.springs.size());
      if (spring && k >= springs)
        return c.name + ": the case has " + std::to_string(springs) + " spring(s) on its floating solids, numbered from 0";
      if (!spring && k >= static_cast<double>(known->bodies.size()))
        return c.name + ": the case has " + std::to_string(known->bodies.size()) + " floating solid(s), numbered from 0";
      if (!spring && !known->bodies[static_cast<std::size_t>(k)].hinge.on)
        return c.name + ": floating solid " + std::to_string(static_cast<int>(k)) + " has no hinge";
    }
  }
  // The value's range (phase_viscosity, face_*, spring_*, hinge_*: the second value, after the number).
  const double v = c.value.back();
  if (v < spec->min || v > spec->max) {
    std::ostringstream s;
    s << c.name << ": " << v << " is outside [" << spec->min << ", " << spec->max << "]" << (spec->unit.empty() ? "" : " " + spec->unit);
    return s.str();
  }
  if (c.name == "insitu_every" && v != std::floor(v)) return "insitu_every: must be a whole number of steps";
  return std::nullopt;
}

void apply(const SteeringChange& c, SteeringTarget& t) {
  if (c.name == "gravity") {
    for (int k = 0; k < 3; ++k) t.params->gravity[k] = static_cast<float>(c.value[k]);
  } else if (c.name == "viscosity") {
    t.params->materials.fluid[0].viscosity = static_cast<float>(c.value[0]);
  } else if (c.name == "phase_viscosity") {
    t.params->materials.fluid[static_cast<int>(c.value[0])].viscosity = static_cast<float>(c.value[1]);
  } else if (c.name == "artificial_viscosity") {
    t.params->artificial_viscosity = static_cast<float>(c.value[0]);
  } else if (c.name == "motion_amplitude") {
    if (t.motions) t.motions->set_amplitude(static_cast<int>(c.value[0]), c.value[1], c.time);
  } else if (c.name == "motion_frequency") {
    if (t.motions) t.motions->set_frequency(static_cast<int>(c.value[0]), c.value[1], c.time);
  } else if (c.name == "face_temperature" || c.name == "face_heat_flux") {
    // A face may change its kind too (an adiabatic face heated, a held face given a flux): the
    // wall pass reads the face's condition every step (backend/particle_updates.hpp).
    FaceCondition& face = t.params->heat.face[static_cast<int>(c.value[0])];
    face.kind = c.name == "face_temperature" ? ThermalCondition::FaceTemperature : ThermalCondition::FaceFlux;
    face.value = static_cast<float>(c.value[1]);
  } else if (c.name.rfind("spring_", 0) == 0 || c.name.rfind("hinge_", 0) == 0) {
    if (!t.bodies) return;
    const int k = static_cast<int>(c.value[0]);
    const bool spring = c.name[0] == 's', stiffness = c.name.ends_with("_stiffness");
    RigidBodies::Coefficients now = spring ? t.bodies->spring(k) : t.bodies->hinge(k);
    (stiffness ? now.stiffness : now.damping) = c.value[1];
    if (spring)
      t.bodies->set_spring(k, now);
    else
      t.bodies->set_hinge(k, now);
  } else if (c.name == "insitu_every") {
    if (t.insitu_every) *t.insitu_every = static_cast<int>(c.value[0]);
  } else if (c.name == "write_checkpoint") {
    t.checkpoint_now = t.checkpoint_now || c.value[0] != 0.0;
  } else if (c.name == "stop") {
    t.stop = t.stop || c.value[0] != 0.0;
  }
}

std::string to_log_line(const SteeringChange& c) {
  std::ostringstream s;
  s << c.step << ' ' << std::setprecision(17) << c.time << ' ' << c.name;
  for (double v : c.value) s << ' ' << v;
  return s.str();
}

namespace {

// A whole token as a number (strtod/strtoll: "inf" and "nan" read as such; a value beyond the
// double range is an error, not infinity).
bool to_double(const std::string& token, double& out, bool& out_of_range) {
  errno = 0;
  char* end = nullptr;
  out = std::strtod(token.c_str(), &end);
  out_of_range = errno == ERANGE && std::fabs(out) > 1.0;
  return end != token.c_str() && *end == '\0';
}

bool to_int64(const std::string& token, std::int64_t& out) {
  errno = 0;
  char* end = nullptr;
  const long long v = std::strtoll(token.c_str(), &end, 10);
  out = v;
  return end != token.c_str() && *end == '\0' && errno != ERANGE;
}

}  // namespace

std::vector<SteeringChange> parse_log(const std::string& text, const std::string& file, std::optional<int> dim) {
  std::vector<SteeringChange> out;
  std::istringstream in(text);
  int line_no = 0;
  for (std::string line; std::getline(in, line);) {
    ++line_no;
    auto fail = [&](const std::string& what) -> std::runtime_error {
      return std::runtime_error(file + ":" + std::to_string(line_no) + ": " + what);
    };
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    std::istringstream s(line);
    std::vector<std::string> tokens;
    for (std::string t; s >> t;) tokens.push_back(t);
    if (tokens.empty()) continue;  // blank or comment line
    if (tokens.size() < 3) throw fail("expected '<step> <time> <name> <values>'");
    SteeringChange c;
    bool range = false;
    if (!to_int64(tokens[0], c.step) || c.step < 0) throw fail("'" + tokens[0] + "' is not a step number (a whole number >= 0)");
    if (!to_double(tokens[1], c.time, range) || range || !std::isfinite(c.time) || c.time < 0)
      throw fail("'" + tokens[1] + "' is not a simulated time (a finite number >= 0)");
    c.name = tokens[2];
    for (std::size_t k = 3; k < tokens.size(); ++k) {
      double v = 0;
      if (!to_double(tokens[k], v, range)) throw fail("'" + tokens[k] + "' is not a number");
      if (range) throw fail(tokens[k] + " is out of range for a double");
      c.value.push_back(v);
    }
    // A recorded log holds only changes that were accepted: anything the live check would reject
    // is a damaged or edited log.
    if (dim)
      if (auto why = validate(c, *dim)) throw fail(*why);
    if (!out.empty() && c.step < out.back().step) throw fail("steps must not decrease");
    out.push_back(std::move(c));
  }
  return out;
}

std::vector<SteeringChange> read_log(const std::string& path, int dim) {
  // A steering log holds a line per change: megabytes of it are not one.
  const std::string text = read_input_text(path, "the steering log", std::size_t{16} << 20);
  if (text.find('\0') != std::string::npos) throw std::runtime_error(path + ": not a steering log (binary data)");
  return parse_log(text, path, dim);
}

std::vector<SteeringChange> SteeringReplay::poll(std::int64_t step, double) {
  std::vector<SteeringChange> now;
  while (next_ < log_.size() && log_[next_].step < step) ++next_;  // older entries: already in the state
  while (next_ < log_.size() && log_[next_].step == step) now.push_back(log_[next_++]);
  return now;
}

}  // namespace spate
