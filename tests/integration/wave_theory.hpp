#pragma once
// Linear water-wave theory for the moving-wall validation (test_moving_walls.cpp) and the signal
// analysis that compares a gauge's time series with it.
#include <cmath>
#include <complex>
#include <numbers>
#include <utility>
#include <vector>

namespace spate::test {

// Wavenumber k of omega^2 = g k tanh(k d) (Newton from the deep-water guess).
inline double wavenumber(double omega, double depth, double g = 9.81) {
  double k = omega * omega / g;
  for (int it = 0; it < 50; ++it) {
    const double t = std::tanh(k * depth);
    const double f = g * k * t - omega * omega;
    const double df = g * t + g * k * depth * (1.0 - t * t);
    k -= f / df;
  }
  return k;
}

// Biesel's piston transfer function: wave height over stroke, H / S = 2 (cosh 2kd - 1) / (sinh 2kd + 2kd).
inline double biesel_height_over_stroke(double k, double depth) {
  const double x = 2.0 * k * depth;
  return 2.0 * (std::cosh(x) - 1.0) / (std::sinh(x) + x);
}

// The first natural frequency of a rectangular tank: omega_n^2 = g (n pi / L) tanh(n pi d / L).
inline double sloshing_frequency(int n, double length, double depth, double g = 9.81) {
  const double k = n * std::numbers::pi / length;
  return std::sqrt(g * k * std::tanh(k * depth));
}

// Linear sloshing in a rectangular tank in sway x_T = A sin(omega t) (Faltinsen 1978; Faltinsen &
// Timokha 2009, ch. 5): the steady-state free-surface elevation at distance xi from the left wall is
//   zeta = (A omega^2 / g) sin(omega t) sum_{n odd} (4 L / (n pi)^2) omega_n^2 / (omega_n^2 - omega^2) cos(n pi xi / L)
// (the first mode rises where the tank accelerates towards; the sign is dropped). Returns its
// amplitude.
inline double sway_response_amplitude(double A, double omega, double length, double depth, double xi, double g = 9.81) {
  double sum = 0.0;
  for (int n = 1; n < 2001; n += 2) {
    const double wn2 = std::pow(sloshing_frequency(n, length, depth, g), 2);
    sum += 4.0 * length / std::pow(n * std::numbers::pi, 2) * wn2 / (wn2 - omega * omega) * std::cos(n * std::numbers::pi * xi / length);
  }
  return std::fabs(A * omega * omega / g * sum);
}

// Zero up-crossing analysis of (t, v) in [t0, t1] about the window's mean: the times of the
// up-crossings, and for every wave between two of them its height (crest minus trough).
struct Waves {
  std::vector<double> crossings, heights;
  double mean_period() const { return (crossings.back() - crossings.front()) / static_cast<double>(crossings.size() - 1); }
  double mean_height() const {
    double s = 0.0;
    for (double h : heights) s += h;
    return s / static_cast<double>(heights.size());
  }
};
inline Waves zero_up_crossings(const std::vector<std::pair<double, double>>& series, double t0, double t1) {
  std::vector<std::pair<double, double>> w;
  double mean = 0.0;
  for (auto [t, v] : series)
    if (t >= t0 && t <= t1) w.emplace_back(t, v), mean += v;
  mean /= static_cast<double>(w.size());
  Waves out;
  double lo = 1e300, hi = -1e300;
  for (std::size_t i = 0; i + 1 < w.size(); ++i) {
    const double a = w[i].second - mean, b = w[i + 1].second - mean;
    if (!out.crossings.empty()) lo = std::min(lo, a + mean), hi = std::max(hi, a + mean);
    if (a < 0.0 && b >= 0.0) {
      out.crossings.push_back(w[i].first - a * (w[i + 1].first - w[i].first) / (b - a));
      if (out.crossings.size() > 1) out.heights.push_back(hi - lo);
      lo = 1e300, hi = -1e300;
    }
  }
  return out;
}

// Least-squares fit of v(t) in [t0, t1] by c0 + sum over the given frequencies of a sin + b cos;
// returns each frequency's phasor C = b + i a, so that its term is Re(C e^{-i omega t}).
inline std::vector<std::complex<double>> harmonic_phasors(const std::vector<std::pair<double, double>>& series, double t0, double t1,
                                                          const std::vector<double>& omegas) {
  const std::size_t n = 1 + 2 * omegas.size();
  std::vector<double> M(n * n, 0.0), r(n, 0.0), f(n);
  for (auto [t, v] : series) {
    if (t < t0 || t > t1) continue;
    f[0] = 1.0;
    for (std::size_t k = 0; k < omegas.size(); ++k) f[1 + 2 * k] = std::sin(omegas[k] * t), f[2 + 2 * k] = std::cos(omegas[k] * t);
    for (std::size_t i = 0; i < n; ++i) {
      r[i] += f[i] * v;
      for (std::size_t j = 0; j < n; ++j) M[i * n + j] += f[i] * f[j];
    }
  }
  // Gaussian elimination with partial pivoting.
  for (std::size_t c = 0; c < n; ++c) {
    std::size_t p = c;
    for (std::size_t i = c + 1; i < n; ++i)
      if (std::fabs(M[i * n + c]) > std::fabs(M[p * n + c])) p = i;
    for (std::size_t j = 0; j < n; ++j) std::swap(M[c * n + j], M[p * n + j]);
    std::swap(r[c], r[p]);
    for (std::size_t i = c + 1; i < n; ++i) {
      const double q = M[i * n + c] / M[c * n + c];
      for (std::size_t j = c; j < n; ++j) M[i * n + j] -= q * M[c * n + j];
      r[i] -= q * r[c];
    }
  }
  std::vector<double> x(n);
  for (std::size_t c = n; c-- > 0;) {
    double s = r[c];
    for (std::size_t j = c + 1; j < n; ++j) s -= M[c * n + j] * x[j];
    x[c] = s / M[c * n + c];
  }
  std::vector<std::complex<double>> out;
  for (std::size_t k = 0; k < omegas.size(); ++k) out.emplace_back(x[2 + 2 * k], x[1 + 2 * k]);
  return out;
}

// The amplitude sqrt(a^2 + b^2) at each frequency of that fit.
inline std::vector<double> harmonic_amplitudes(const std::vector<std::pair<double, double>>& series, double t0, double t1,
                                               const std::vector<double>& omegas) {
  std::vector<double> out;
  for (const std::complex<double>& c : harmonic_phasors(series, t0, t1, omegas)) out.push_back(std::abs(c));
  return out;
}

// Incident and reflected waves from two gauges (Goda & Suzuki 1976): the phasors A1, A2 at x1, x2 of
// a_I e^{ikx} + a_R e^{-ikx}; returns (a_I, a_R). k (x2 - x1) must stay clear of multiples of pi.
inline std::pair<std::complex<double>, std::complex<double>> incident_and_reflected(std::complex<double> A1, std::complex<double> A2,
                                                                                   double x1, double x2, double k) {
  const std::complex<double> i(0.0, 1.0);
  const std::complex<double> e1 = std::exp(i * k * x1), e2 = std::exp(i * k * x2);
  const std::complex<double> det = e1 / e2 - e2 / e1;
  return {(A1 / e2 - A2 / e1) / det, (e1 * A2 - e2 * A1) / det};
}

}  // namespace spate::test
