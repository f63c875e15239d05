#pragma once
// Smoothing kernels with compact support 2h (design.md). Each kernel gives
//   W(r)                       value
//   F(r) = (dW/dr) / r         so that grad_i W_ij = F * r_ij  (no division by r in the pair loop)
// normalised for 2D and 3D. `norm` is the dimensional constant alpha_d / h^Dim, set once per run.
#include <cmath>

#include "host_device.hpp"

namespace spate {

enum class KernelType { WendlandC2, CubicSpline };

constexpr float kPi = 3.14159265358979323846f;

// Wendland C2 (Wendland 1995; Dehnen & Aly 2012), support q = r/h in [0, 2):
//   W = alpha_d (1 - q/2)^4 (2q + 1), alpha_2D = 7/(4 pi h^2), alpha_3D = 21/(16 pi h^3)
struct WendlandC2 {
  static constexpr KernelType type = KernelType::WendlandC2;
  static float normalisation(int dim, float h) {
    return dim == 2 ? 7.0f / (4.0f * kPi * h * h) : 21.0f / (16.0f * kPi * h * h * h);
  }
  SPATE_HD static float value(float q, float norm) {
    if (q >= 2.0f) return 0.0f;
    const float t = 1.0f - 0.5f * q;
    const float t2 = t * t;
    return norm * t2 * t2 * (2.0f * q + 1.0f);
  }
  // dW/dr = norm * (-5 q / h) (1 - q/2)^3, so F = dW/dr / r = -5 norm (1 - q/2)^3 / h^2.
  // Branch-free (exactly 0 for q >= 2) so that pair loops vectorise.
  SPATE_HD static float gradient_factor(float q, float norm, float inv_h2) {
    const float u = 1.0f - 0.5f * q;
    const float t = u > 0.0f ? u : 0.0f;
    return -5.0f * norm * t * t * t * inv_h2;
  }
};

// Cubic B-spline (Monaghan & Lattanzio 1985), alpha_2D = 10/(7 pi h^2), alpha_3D = 1/(pi h^3):
//   W = alpha (1 - 1.5 q^2 + 0.75 q^3) for q < 1, alpha 0.25 (2 - q)^3 for 1 <= q < 2
struct CubicSpline {
  static constexpr KernelType type = KernelType::CubicSpline;
  static float normalisation(int dim, float h) {
    return dim == 2 ? 10.0f / (7.0f * kPi * h * h) : 1.0f / (kPi * h * h * h);
  }
  SPATE_HD static float value(float q, float norm) {
    if (q >= 2.0f) return 0.0f;
    if (q < 1.0f) return norm * (1.0f - 1.5f * q * q + 0.75f * q * q * q);
    const float t = 2.0f - q;
    return norm * 0.25f * t * t * t;
  }
  // dW/dq = alpha (-3q + 2.25 q^2) for q<1, -0.75 alpha (2-q)^2 otherwise; F = dW/dq / (h r) = dW/dq / (q h^2)
  // Branch-free (selects), exactly 0 for q >= 2.
  SPATE_HD static float gradient_factor(float q, float norm, float inv_h2) {
    const float inner = norm * (-3.0f + 2.25f * q) * inv_h2;
    const float u = 2.0f - q;
    const float t = u > 0.0f ? u : 0.0f;
    const float outer = -0.75f * norm * t * t / (q > 1.0f ? q : 1.0f) * inv_h2;
    return q < 1.0f ? inner : outer;
  }
};

// Gradient renormalisation on the initial particle lattice. On a regular lattice of spacing dp the
// discrete second moment  -sum_j V_j (x_j - x_i)_x (grad_i W_ij)_x  is not exactly 1 (0.974 for
// Wendland C2 in 2D at h = 1.3 dp): every SPH gradient and divergence is off by that factor, and a
// hydrostatic column then needs a few percent more pressure than rho g d to stand. Dividing the
// gradient by the lattice moment (computed once per run) makes the operator exact for linear
// fields on the undisturbed lattice, where most of the fluid spends its life. With eta2, the moment of
// the conduction operator (heat_transfer.hpp), whose pair factor carries r^2 / (r^2 + eta^2).
template <class Kernel>
double lattice_gradient_moment(int dim, double h, double dp, double eta2 = 0.0) {
  const float norm = Kernel::normalisation(dim, static_cast<float>(h));
  const float inv_h2 = static_cast<float>(1.0 / (h * h));
  const int reach = static_cast<int>(2.0 * h / dp) + 1;
  double moment = 0.0;
  const double volume = dim == 2 ? dp * dp : dp * dp * dp;
  for (int i = -reach; i <= reach; ++i)
    for (int j = -reach; j <= reach; ++j)
      for (int k = dim == 3 ? -reach : 0; k <= (dim == 3 ? reach : 0); ++k) {
        const double r2 = (double(i) * i + double(j) * j + double(k) * k) * dp * dp;
        if (r2 == 0.0) continue;
        const float F = Kernel::gradient_factor(static_cast<float>(std::sqrt(r2) / h), norm, inv_h2);
        // -(x_j - x_i)_x * F * (x_i - x_j)_x; with eta2 > 0 times the Laplacian's r^2 / (r^2 + eta^2)
        // (heat_transfer.hpp; eta2 = 0 multiplies by exactly 1).
        moment += volume * (i * dp) * (i * dp) * F * (r2 / (r2 + eta2));
      }
  return -moment;
}

}  // namespace spate
