#include "motion.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace spate {

namespace {

constexpr double kPiMotion = 3.14159265358979323846;

Jet operator*(const Jet& a, const Jet& b) { return {a.v * b.v, a.d * b.v + a.v * b.d, a.dd * b.v + 2.0 * a.d * b.d + a.v * b.dd}; }
Jet operator*(double s, const Jet& a) { return {s * a.v, s * a.d, s * a.dd}; }

// 0 before t = 0, 1 after t = T, a half cosine in between (continuous velocity).
Jet smooth_step(double t, double T) {
  if (t <= 0.0) return {T > 0.0 ? 0.0 : (t < 0.0 ? 0.0 : 1.0), 0.0, 0.0};
  if (t >= T) return {1.0, 0.0, 0.0};
  const double w = kPiMotion / T;
  return {0.5 * (1.0 - std::cos(w * t)), 0.5 * w * std::sin(w * t), 0.5 * w * w * std::cos(w * t)};
}

Jet sine(double omega, double phase, double t) {
  const double a = omega * t + phase;
  return {std::sin(a), omega * std::cos(a), -omega * omega * std::sin(a)};
}

// Natural cubic spline through (x_i, y_i): second derivatives at the knots.
std::vector<double> spline_moments(const std::vector<double>& x, const std::vector<double>& y) {
  const std::size_t n = x.size();
  std::vector<double> m(n, 0.0);
  if (n < 3) return m;
  std::vector<double> diag(n, 0.0), upper(n, 0.0), rhs(n, 0.0);
  for (std::size_t i = 1; i + 1 < n; ++i) {
    const double h0 = x[i] - x[i - 1], h1 = x[i + 1] - x[i];
    diag[i] = 2.0 * (h0 + h1);
    upper[i] = h1;
    rhs[i] = 6.0 * ((y[i + 1] - y[i]) / h1 - (y[i] - y[i - 1]) / h0);
  }
  // Thomas algorithm on rows 1 .. n-2 (m_0 = m_{n-1} = 0).
  for (std::size_t i = 2; i + 1 < n; ++i) {
    const double lower = x[i] - x[i - 1];
    const double f = lower / diag[i - 1];
    diag[i] -= f * upper[i - 1];
    rhs[i] -= f * rhs[i - 1];
  }
  for (std::size_t i = n - 2; i >= 1; --i) {
    m[i] = (rhs[i] - (i + 2 < n ? upper[i] * m[i + 1] : 0.0)) / diag[i];
    if (i == 1) break;
  }
  return m;
}

Jet spline(const std::vector<double>& x, const std::vector<double>& y, const std::vector<double>& m, double t) {
  const std::size_t n = x.size();
  if (n == 0) return {};
  if (t <= x.front()) return {y.front(), 0.0, 0.0};
  if (t >= x.back()) return {y.back(), 0.0, 0.0};
  const std::size_t i = static_cast<std::size_t>(std::upper_bound(x.begin(), x.end(), t) - x.begin()) - 1;
  const double h = x[i + 1] - x[i], a = (x[i + 1] - t) / h, b = (t - x[i]) / h;
  Jet j;
  j.v = a * y[i] + b * y[i + 1] + ((a * a * a - a) * m[i] + (b * b * b - b) * m[i + 1]) * h * h / 6.0;
  j.d = (y[i + 1] - y[i]) / h - (3.0 * a * a - 1.0) * h * m[i] / 6.0 + (3.0 * b * b - 1.0) * h * m[i + 1] / 6.0;
  j.dd = a * m[i] + b * m[i + 1];
  return j;
}

// Rotation by `angle` about the unit `axis` (Rodrigues).
void rotation_matrix(const Vec3& axis, double angle, double R[3][3]) {
  const double c = std::cos(angle), s = std::sin(angle), C = 1.0 - c;
  const double x = axis[0], y = axis[1], z = axis[2];
  R[0][0] = c + x * x * C, R[0][1] = x * y * C - z * s, R[0][2] = x * z * C + y * s;
  R[1][0] = y * x * C + z * s, R[1][1] = c + y * y * C, R[1][2] = y * z * C - x * s;
  R[2][0] = z * x * C - y * s, R[2][1] = z * y * C + x * s, R[2][2] = c + z * z * C;
}

}  // namespace

bool body_support() {
#ifdef SPATE_WITH_BODIES
  return true;
#else
  return false;
#endif
}

MotionSet::MotionSet(std::vector<MotionSpec> specs, int dim) : dim_(dim), specs_(std::move(specs)) {
  for (const MotionSpec& s : specs_) {
    Segment first;
    first.start = -std::numeric_limits<double>::infinity();
    first.omega = s.omega;
    first.phase = s.phase;
    segments_.push_back({first});
    std::array<std::vector<double>, 4> columns, moments;
    for (int c = 0; c < 4; ++c) {
      for (const auto& v : s.values) columns[c].push_back(v[c]);
      moments[c] = spline_moments(s.times, columns[c]);
    }
    columns_.push_back(std::move(columns));
    moments_.push_back(std::move(moments));
  }
}

const MotionSet::Segment& MotionSet::segment(int k, double t) const {
  const auto& list = segments_[k];
  std::size_t at = 0;
  for (std::size_t i = 0; i < list.size(); ++i)
    if (list[i].start <= t) at = i;
  return list[at];
}

// Ramp-up, ramp-down and the steered amplitude scale.
Jet MotionSet::envelope(int k, double t) const {
  const MotionSpec& s = specs_[k];
  Jet e = smooth_step(t, s.ramp);
  if (s.end) {
    if (t >= *s.end) return {};
    const Jet down = smooth_step(t - (*s.end - s.end_ramp), s.end_ramp);
    e = e * Jet{1.0 - down.v, -down.d, -down.dd};
  }
  const Segment& g = segment(k, t);
  const Jet blend = smooth_step(t - g.blend_start, g.blend);
  const Jet scale{g.scale_from + (g.scale_to - g.scale_from) * blend.v, (g.scale_to - g.scale_from) * blend.d,
                  (g.scale_to - g.scale_from) * blend.dd};
  return e * scale;
}

namespace {

// Rodrigues: r turned by `angle` about the unit axis n.
Vec3 rotated(const Vec3& n, double angle, const Vec3& r) {
  const double cs = std::cos(angle), sn = std::sin(angle);
  const double n_dot_r = n[0] * r[0] + n[1] * r[1] + n[2] * r[2];
  const double cross[3] = {n[1] * r[2] - n[2] * r[1], n[2] * r[0] - n[0] * r[2], n[0] * r[1] - n[1] * r[0]};
  Vec3 out{0, 0, 0};
  for (int k = 0; k < 3; ++k) out[k] = r[k] * cs + cross[k] * sn + n[k] * n_dot_r * (1.0 - cs);
  return out;
}

}  // namespace

Vec3 moved_point(const MotionSpec& m, const MotionSample& s, const Vec3& x0) {
  const Vec3 r = rotated(m.axis, s.angle, {x0[0] - m.centre[0], x0[1] - m.centre[1], x0[2] - m.centre[2]});
  return {m.centre[0] + s.displacement[0] + r[0], m.centre[1] + s.displacement[1] + r[1], m.centre[2] + s.displacement[2] + r[2]};
}

Vec3 start_point(const MotionSpec& m, const MotionSample& s, const Vec3& x) {
  Vec3 r{0, 0, 0};
  for (int k = 0; k < 3; ++k) r[k] = x[k] - m.centre[k] - s.displacement[k];
  const Vec3 back = rotated(m.axis, -s.angle, r);
  return {m.centre[0] + back[0], m.centre[1] + back[1], m.centre[2] + back[2]};
}

Vec3 turned(const MotionSpec& m, const MotionSample& s, const Vec3& v) { return rotated(m.axis, s.angle, v); }

Vec3 point_velocity(const MotionSpec& m, const MotionSample& s, const Vec3& x) {
  Vec3 r{0, 0, 0};
  for (int k = 0; k < 3; ++k) r[k] = x[k] - m.centre[k] - s.displacement[k];
  const Vec3& n = m.axis;
  const double w = s.angular_velocity;
  return {s.velocity[0] + w * (n[1] * r[2] - n[2] * r[1]), s.velocity[1] + w * (n[2] * r[0] - n[0] * r[2]),
          s.velocity[2] + w * (n[0] * r[1] - n[1] * r[0])};
}

MotionSample MotionSet::sample(int k, double t) const {
  const MotionSpec& s = specs_[k];
  const Jet e = envelope(k, t);
  MotionSample out;
  auto put = [](const Jet& j, double& v, double& d, double& dd) { v = j.v, d = j.d, dd = j.dd; };
  if (s.sinusoid()) {
    const Segment& g = segment(k, t);
    const Jet q = e * sine(g.omega, g.phase, t);
    for (int a = 0; a < 3; ++a) put(s.translation[a] * q, out.displacement[a], out.velocity[a], out.acceleration[a]);
    put(s.rotation * q, out.angle, out.angular_velocity, out.angular_acceleration);
  } else {
    for (int c = 0; c < 4; ++c) {
      const Jet q = e * spline(s.times, columns_[k][c], moments_[k][c], t);
      if (c < 3) put(q, out.displacement[c], out.velocity[c], out.acceleration[c]);
      else put(q, out.angle, out.angular_velocity, out.angular_acceleration);
    }
  }
  return out;
}

Vec3 MotionSet::bound() const {
  Vec3 b{0, 0, 0};
  for (const MotionSpec& s : specs_) {
    if (s.floating >= 0) {  // a floating solid goes where the water takes it, inside the tank, turning in place
      for (int a = 0; a < dim_; ++a) b[a] += s.reach;
      continue;
    }
    double translation[3] = {std::fabs(s.translation[0]), std::fabs(s.translation[1]), std::fabs(s.translation[2])};
    double angle = std::fabs(s.rotation);
    if (!s.sinusoid()) {
      translation[0] = translation[1] = translation[2] = angle = 0.0;
      // Splines overshoot their samples a little between them.
      for (const auto& v : s.values) {
        for (int a = 0; a < 3; ++a) translation[a] = std::max(translation[a], 1.25 * std::fabs(v[a]));
        angle = std::max(angle, 1.25 * std::fabs(v[3]));
      }
    }
    // A point at distance `reach` from the centre sweeps at most angle x reach.
    for (int a = 0; a < dim_; ++a) b[a] += kMaxMotionAmplitudeScale * (translation[a] + std::min(angle, kPiMotion) * s.reach);
  }
  return b;
}

void MotionSet::set_step(PhysicsParams& P, double t0, double t1) const {
  P.motions = size();
  for (int k = 0; k < size(); ++k) {
    const MotionSpec& s = specs_[k];
    if (s.floating >= 0) continue;  // RigidBodies::set_step
    const MotionSample a = sample(k, t0), b = sample(k, t1);
    MotionState& m = P.motion[k];
    MotionStep& step = P.motion_step[k];
    for (int c = 0; c < 3; ++c) {
      m.velocity[c] = static_cast<float>(b.velocity[c]);
      m.acceleration[c] = static_cast<float>(b.acceleration[c]);
      m.centre[c] = static_cast<float>(s.centre[c] + b.displacement[c]);
      m.angular_velocity[c] = static_cast<float>(b.angular_velocity * s.axis[c]);
      m.angular_acceleration[c] = static_cast<float>(b.angular_acceleration * s.axis[c]);
      step.from[c] = s.centre[c] + a.displacement[c];
      step.to[c] = s.centre[c] + b.displacement[c];
    }
    rotation_matrix(s.axis, b.angle - a.angle, step.rotation);
  }
}

std::optional<std::string> MotionSet::check_amplitude(int k, double scale) const {
  if (k < 0 || k >= size()) return "the case has " + std::to_string(size()) + " motion(s); there is no motion " + std::to_string(k);
  if (specs_[k].floating >= 0) return "motion " + std::to_string(k) + " (" + specs_[k].body + ") is a floating solid: the water moves it";
  if (!(scale >= 0.0 && scale <= kMaxMotionAmplitudeScale))
    return "amplitude scale " + std::to_string(scale) + " is outside [0, " + std::to_string(kMaxMotionAmplitudeScale) + "]";
  return std::nullopt;
}

std::optional<std::string> MotionSet::check_frequency(int k, double hertz) const {
  if (k < 0 || k >= size()) return "the case has " + std::to_string(size()) + " motion(s); there is no motion " + std::to_string(k);
  if (specs_[k].floating >= 0) return "motion " + std::to_string(k) + " (" + specs_[k].body + ") is a floating solid: the water moves it";
  if (!specs_[k].sinusoid()) return "motion " + std::to_string(k) + " (" + specs_[k].body + ") is a time series; only a sinusoid has a frequency";
  if (!(hertz > 0.0 && hertz <= 100.0)) return "frequency " + std::to_string(hertz) + " Hz is outside (0, 100]";
  return std::nullopt;
}

void MotionSet::set_amplitude(int k, double scale, double time) {
  Segment next = segment(k, time);
  const Jet blend = smooth_step(time - next.blend_start, next.blend);
  next.scale_from = next.scale_from + (next.scale_to - next.scale_from) * blend.v;  // the scale now
  next.scale_to = scale;
  next.start = next.blend_start = time;
  next.blend = specs_[k].sinusoid() && next.omega > 0 ? 2.0 * kPiMotion / next.omega : 1.0;
  segments_[k].push_back(next);
}

void MotionSet::set_frequency(int k, double hertz, double time) {
  Segment next = segment(k, time);
  const double omega = 2.0 * kPiMotion * hertz;
  next.phase += (next.omega - omega) * time;  // omega t + phase is continuous at `time`
  next.omega = omega;
  next.start = time;
  segments_[k].push_back(next);
}

double MotionSet::frequency(int k) const {
  const auto& list = segments_[k];
  return specs_[k].sinusoid() ? list.back().omega / (2.0 * kPiMotion) : 0.0;
}

void read_motion_csv(const std::string& path, MotionSpec& spec) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot read the motion time series");
  spec.file = path;
  std::string line;
  int line_no = 0;
  std::vector<int> column_of;  // per CSV column: -1 time, 0..2 x y z, 3 angle, -2 ignored
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty() || line[0] == '#') continue;
    std::vector<std::string> cells;
    std::stringstream s(line);
    for (std::string cell; std::getline(s, cell, ',');) {
      const auto a = cell.find_first_not_of(" \t\r"), b = cell.find_last_not_of(" \t\r");
      cells.push_back(a == std::string::npos ? std::string() : cell.substr(a, b - a + 1));
    }
    if (column_of.empty()) {
      bool has_time = false;
      for (const std::string& name : cells) {
        const int c = name == "time" ? -1 : name == "x" ? 0 : name == "y" ? 1 : name == "z" ? 2 : name == "angle" ? 3 : -2;
        if (c == -2)
          throw std::runtime_error(path + ":" + std::to_string(line_no) + ": unknown column '" + name +
                                   "' (expected time, x, y, z, angle)");
        has_time = has_time || c == -1;
        column_of.push_back(c);
      }
      if (!has_time) throw std::runtime_error(path + ":" + std::to_string(line_no) + ": the header has no 'time' column");
      continue;
    }
    if (cells.size() != column_of.size())
      throw std::runtime_error(path + ":" + std::to_string(line_no) + ": expected " + std::to_string(column_of.size()) + " values");
    double t = 0.0;
    std::array<double, 4> v{0, 0, 0, 0};
    for (std::size_t c = 0; c < cells.size(); ++c) {
      double x = 0.0;
      try {
        std::size_t used = 0;
        x = std::stod(cells[c], &used);
        if (used != cells[c].size() || !std::isfinite(x)) throw std::invalid_argument("");
      } catch (const std::exception&) {
        throw std::runtime_error(path + ":" + std::to_string(line_no) + ": '" + cells[c] + "' is not a number");
      }
      if (column_of[c] == -1) t = x;
      else v[column_of[c]] = column_of[c] == 3 ? x * kPiMotion / 180.0 : x;
    }
    if (!spec.times.empty() && !(t > spec.times.back()))
      throw std::runtime_error(path + ":" + std::to_string(line_no) + ": times must increase");
    spec.times.push_back(t);
    spec.values.push_back(v);
  }
  if (spec.times.size() < 2) throw std::runtime_error(path + ": a motion time series needs at least 2 rows");
}

}  // namespace spate
