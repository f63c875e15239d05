#include "flow_drive.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace spate {

FlowDrive::FlowDrive(const Case& c) : spec_(c.drive), dim_(c.dim) {
  for (int k = 0; k < 3; ++k) force_[k] = c.body_force[k];  // the case's body force is the first guess
}

void FlowDrive::update(PhysicsParams& P, const std::array<double, 3>& mean_velocity, double dt_taken, double dt_next) {
  if (!spec_.on) return;
  for (int k = 0; k < dim_; ++k) {
    if (!spec_.axes[k]) continue;
    // The deceleration the last step showed (none known before the first step).
    const double deceleration = has_last_ && dt_taken > 0 ? force_[k] - (mean_velocity[k] - last_mean_[k]) / dt_taken : force_[k];
    force_[k] = deceleration + (spec_.mean_velocity[k] - mean_velocity[k]) / std::max(spec_.response_time, dt_next);
    last_mean_[k] = mean_velocity[k];
  }
  has_last_ = true;
  apply(P);
}

void FlowDrive::apply(PhysicsParams& P) const {
  if (!spec_.on) return;
  for (int k = 0; k < dim_; ++k)
    if (spec_.axes[k]) P.body_force[k] = static_cast<float>(force_[k]);
}

std::string FlowDrive::save() const {
  if (!spec_.on) return {};
  std::string out = has_last_ ? "force" : "start force";
  for (double v : force_) out += fmt::format(" {:a}", v);
  out += " mean";
  for (double v : last_mean_) out += fmt::format(" {:a}", v);
  return out + "\n";
}

void FlowDrive::restore(const std::string& text) {
  if (!spec_.on) {
    if (!text.empty()) throw std::runtime_error("it holds a flow drive's state, and the case has no drive");
    return;
  }
  if (text.empty()) throw std::runtime_error("the case has a drive, and the checkpoint holds no drive state");
  std::istringstream in(text);
  std::string word;
  in >> word;
  bool has_last = true;
  if (word == "start") has_last = false, in >> word;
  if (word != "force") throw std::runtime_error("expected 'force' at the start of the drive state");
  std::array<double, 3> force{}, mean{};
  auto read = [&](std::array<double, 3>& v) {
    for (double& x : v) {
      if (!(in >> word)) throw std::runtime_error("the drive state is cut short");
      std::size_t used = 0;
      try {
        x = std::stod(word, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (used != word.size() || !std::isfinite(x)) throw std::runtime_error("'" + word + "' in the drive state is not a finite number");
    }
  };
  read(force);
  if (!(in >> word) || word != "mean") throw std::runtime_error("expected 'mean' after the drive's force");
  read(mean);
  if (in >> word) throw std::runtime_error("unexpected '" + word + "' after the drive state");
  force_ = force, last_mean_ = mean, has_last_ = has_last;
}

}  // namespace spate
