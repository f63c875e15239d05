#include "growth.hpp"

#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace spate {

namespace {

struct Trial {
  double c = 0, d = 0, error = std::numeric_limits<double>::infinity();
};

// C and D for a given n: weighted least squares with weights 1/a^2 (relative error).
Trial solve(const std::vector<std::pair<double, double>>& s, double n) {
  double aa = 0, ab = 0, bb = 0, ya = 0, yb = 0;
  for (auto [t, a] : s) {
    const double w = 1.0 / (a * a), e = std::exp(n * t), f = std::exp(-n * t);
    aa += w * e * e, ab += w * e * f, bb += w * f * f, ya += w * a * e, yb += w * a * f;
  }
  Trial out;
  const double det = aa * bb - ab * ab;
  if (!(std::fabs(det) > 1e-300)) return out;
  out.c = (ya * bb - yb * ab) / det;
  out.d = (aa * yb - ab * ya) / det;
  out.error = 0;
  for (auto [t, a] : s) {
    const double r = (out.c * std::exp(n * t) + out.d * std::exp(-n * t) - a) / a;
    out.error += r * r;
  }
  return out;
}

}  // namespace

GrowthFit fit_growth(const std::vector<std::pair<double, double>>& samples, double until) {
  std::vector<std::pair<double, double>> s;
  for (auto [t, a] : samples) {
    if (!(a <= until)) break;  // the linear range ends (a NaN ends it too)
    if (a > 0) s.emplace_back(t, a);
  }
  if (s.size() < 4) throw std::invalid_argument("fewer than 4 positive samples before the amplitude exceeds the linear range's limit");
  const double span = s.back().first - s.front().first;
  if (!(span > 0)) throw std::invalid_argument("the samples span no time");
  // Scan n over [0, 20/span] (a growth by e^20 at most), then refine by golden section.
  const int kScan = 400;
  const double top = 20.0 / span;
  double best_n = 0, best = std::numeric_limits<double>::infinity();
  for (int k = 0; k <= kScan; ++k) {
    const double n = top * k / kScan;
    const double e = solve(s, n).error;
    if (e < best) best = e, best_n = n;
  }
  double lo = std::max(0.0, best_n - top / kScan), hi = best_n + top / kScan;
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  for (int it = 0; it < 100; ++it) {
    const double m1 = hi - g * (hi - lo), m2 = lo + g * (hi - lo);
    if (solve(s, m1).error < solve(s, m2).error) hi = m2;
    else lo = m1;
  }
  GrowthFit fit;
  fit.rate = 0.5 * (lo + hi);
  const Trial t = solve(s, fit.rate);
  fit.growing = t.c;
  fit.decaying = t.d;
  fit.from = s.front().first;
  fit.to = s.back().first;
  fit.samples = static_cast<int>(s.size());
  fit.rms = std::sqrt(t.error / static_cast<double>(s.size()));
  return fit;
}

double rayleigh_taylor_rate(double atwood, double g, double k, double nu) {
  const double damping = nu * k * k;
  return std::sqrt(atwood * g * k + damping * damping) - damping;
}

std::vector<std::pair<double, double>> read_probe_column(const std::string& csv, const std::string& column) {
  std::ifstream in(csv);
  if (!in) throw std::runtime_error(csv + ": cannot be read");
  std::string line;
  if (!std::getline(in, line)) throw std::runtime_error(csv + ": empty (expected a probe CSV header)");
  int index = -1, k = 0;
  std::string names;
  std::istringstream header(line);
  for (std::string name; std::getline(header, name, ','); ++k) {
    const std::string bare = name.substr(0, name.find('['));
    if (k >= 2) names += (names.empty() ? "" : ", ") + bare;
    if (k >= 2 && bare == column) index = k;
  }
  if (index < 0) throw std::runtime_error(csv + ": no column '" + column + "' (columns: " + names + ")");
  std::vector<std::pair<double, double>> out;
  int row = 1;
  while (std::getline(in, line)) {
    ++row;
    std::vector<double> v;
    std::istringstream cells(line);
    for (std::string cell; std::getline(cells, cell, ',');) {
      char* end = nullptr;
      v.push_back(std::strtod(cell.c_str(), &end));
      if (end == cell.c_str()) v.back() = std::numeric_limits<double>::quiet_NaN();
    }
    if (static_cast<int>(v.size()) <= index) throw std::runtime_error(csv + ": line " + std::to_string(row) + " has too few columns");
    out.emplace_back(v[0], v[index]);
  }
  return out;
}

}  // namespace spate
