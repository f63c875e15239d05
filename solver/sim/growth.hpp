#pragma once
// The growth rate of an instability from a sampled amplitude a(t) (an interface probe's column):
// the linear solution from any start, a growing and a decaying mode,
//   a(t) = C e^{n t} + D e^{-n t},
// fitted in the linear range (the samples before a first exceeds `until`), by least squares on the
// relative error (each sample counts alike at a0 and at 10 a0): for each n, C and D are linear;
// n is found by a scan and a golden-section refinement. A fit of log a alone would take the
// decaying mode for slower growth (a0 cosh(n t) has slope n tanh(n t), 0.76 n at n t = 1).
// Shared by `spate growth`, the Rayleigh-Taylor validation test and docs/validation.md's figure.
#include <string>
#include <utility>
#include <vector>

namespace spate {

struct GrowthFit {
  double rate = 0.0;         // n [1/s]
  double growing = 0.0;      // C
  double decaying = 0.0;     // D
  double from = 0.0, to = 0.0;  // the samples' times [s]
  int samples = 0;
  double rms = 0.0;          // the fit's root-mean-square relative error
};

// Throws std::invalid_argument when fewer than 4 positive samples lie in the linear range.
GrowthFit fit_growth(const std::vector<std::pair<double, double>>& samples, double until);

// Linear theory of the Rayleigh-Taylor instability with viscosity (two fluids of one kinematic
// viscosity nu; Chandrasekhar 1961, the approximation used by Duff, Harlow & Hirt 1962):
//   n = sqrt(A g k + nu^2 k^4) - nu k^2,  A = (rho_h - rho_l) / (rho_h + rho_l).
double rayleigh_taylor_rate(double atwood, double g, double k, double nu);

// The (time, value) samples of column `column` of a probe CSV (its header name up to '[', e.g.
// "amplitude"); throws std::runtime_error naming the file and the reason.
std::vector<std::pair<double, double>> read_probe_column(const std::string& csv, const std::string& column);

}  // namespace spate
