#pragma once
// Tait equation of state, eq. 9 of the paper, per fluid material:
//   p = c0^2 rho0 / gamma ((rho/rho0)^gamma - 1) + p_b
// with p_b the material's background pressure (0 unless a light phase needs one).
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "host_device.hpp"
#include "materials.hpp"
#include "params.hpp"

namespace spate {

// gamma = 7 as an exact product: pow() would cost more than the rest of the particle update.
SPATE_HD float pow7(float x) {
  const float x2 = x * x;
  const float x3 = x2 * x;
  return x3 * x3 * x;
}

// x^gamma with the exact product for the usual gamma = 7.
SPATE_HD float tait_power(float x, float gamma) { return gamma == 7.0f ? pow7(x) : powf(x, gamma); }

// A float's bits as an integer, and back (the same on the host and the device).
SPATE_HD std::int32_t float_bits(float x) {
#if defined(__CUDA_ARCH__)
  return __float_as_int(x);
#else
  std::int32_t bits;
  std::memcpy(&bits, &x, sizeof bits);
  return bits;
#endif
}
SPATE_HD float bits_float(std::int32_t bits) {
#if defined(__CUDA_ARCH__)
  return __int_as_float(bits);
#else
  float x;
  std::memcpy(&x, &bits, sizeof x);
  return x;
#endif
}

// x^(1/7) for the usual gamma = 7, from + - * / alone (each IEEE-rounded on the CPU and the GPU),
// so that both round it to the same bits: powf's last bit differs between glibc and CUDA's
// library, and the wall state (tait_density with fluid.portable_eos) runs every step. NaN below
// 0, as powf.
SPATE_HD float seventh_root(float x) {
  if (!(x >= 0.0f)) return std::numeric_limits<float>::quiet_NaN();      // below 0, -inf, NaN
  if (x == 0.0f || x == std::numeric_limits<float>::infinity()) return x;  // 0 and +inf are their own root
  // The start: the exponent divided by 7 on the float's bits (a few percent off); then Newton's
  // iteration y <- (6 y + x / y^6) / 7 in double precision, five times (the relative error goes
  // 5e-2, 8e-3, 2e-4, 1e-7, 2e-14, rounding), rounded once to float: the correctly rounded root but
  // where it lies within about 1e-7 ulp of a rounding boundary.
  const std::int32_t bits = (float_bits(x) - 0x3f800000) / 7 + 0x3f800000;
  double y = bits_float(bits);
  const double xd = x;
  for (int n = 0; n < 5; ++n) {
    const double y2 = y * y;
    const double y6 = y2 * y2 * y2;
    y = (6.0 * y + xd / y6) / 7.0;
  }
  return static_cast<float>(y);
}

// x^(1/gamma) with seventh_root for the usual gamma = 7.
SPATE_HD float tait_root(float x, float gamma, float inv_gamma) { return gamma == 7.0f ? seventh_root(x) : powf(x, inv_gamma); }

SPATE_HD float tait_pressure(float rho, const FluidMaterial& m) {
  return m.tait_b * (tait_power(rho / m.rho0, m.gamma) - 1.0f) + m.background_pressure;
}

// The pressure a fluid particle carries: eq. 9, and with fluid.tension off not below 0. A free
// surface is at atmospheric pressure: a stretching sheet of water (a run-up jet, a splash) loses
// density in the weakly compressible model and would otherwise pull on itself and on the walls it
// slides along with a tension real water at atmospheric pressure does not sustain.
SPATE_HD float fluid_pressure(const PhysicsParams& P, const FluidMaterial& m, float rho) {
  const float p = tait_pressure(rho, m);
  return P.tension || p > 0.0f ? p : 0.0f;
}

// The floor of fluid material m's continuity density: its rest density when the fluid takes no
// tension (fluid.tension: false; eos.hpp fluid_pressure clips the pressure at 0), 0 otherwise.
SPATE_HD float density_floor(const PhysicsParams& P, std::uint8_t m) { return P.tension ? 0.0f : P.materials.of(m).rho0; }

// Inverse of eq. 9, used to give wall particles the density that matches their pressure.
// portable (fluid.portable_eos): the root by tait_root, the same bits on the CPU and the GPU;
// otherwise the C library's powf, as before it: every shipped result was computed that way, and the
// impact cases' first peaks are one draw of a chaotic splash that a last-bit change redraws
// (docs/gpu.md), so the default stays until their tests stand on more than one draw.
SPATE_HD float tait_density(float p, const FluidMaterial& m, bool portable = false) {
  const float x = (p - m.background_pressure) / m.tait_b + 1.0f;
  return m.rho0 * (portable ? tait_root(x, m.gamma, m.inv_gamma) : powf(x, m.inv_gamma));
}

// (c / c0)^2 = (rho / rho0)^(gamma - 1): the Tait sound speed at density ratio s, squared and
// relative to c0. Gamma7 (a compile-time choice of the pair loops) keeps the exact product.
template <bool Gamma7>
SPATE_HD float tait_sound_speed_ratio2(float s, float gamma) {
  if constexpr (Gamma7) {
    const float s2 = s * s;
    return s2 * s2 * s2;
  } else {
    return powf(s, gamma - 1.0f);
  }
}

}  // namespace spate
