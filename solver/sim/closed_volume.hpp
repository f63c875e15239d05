#pragma once
// A fluid that fills its container (case key `density.closed_volume`): a periodic channel, a closed
// box without a free surface. Its particles' volumes m / rho must then add up to the container's
// (less its solids) at every step, whatever the flow does: with fixed masses, the mean of rho0 / rho
// is fixed, and with it the pressure level. The continuity density does not keep it by itself. Past
// a cylinder with volume-consistent shifting (docs/studies/cylinder-flow.md) the flow's compression
// and the shift's expansion of the particles are opposite terms of eq. 6 two hundred times the
// drift they leave: the mean density climbed 3 kg/m^3 in 25 s (the mean pressure 80 Pa) while the
// particles' arrangement (their summation density) stayed as dense as at the start, and the rising
// pressure level damped the wake's shedding. Here, after each step, the sum S = sum_i rho0_i / rho_i
// over every fluid particle (exact integer sums of fixed-point terms, the same on every slab for any
// split) is compared with its value at the start S0; once it is off by more than kTolerance (a
// density change of 1e-3 kg/m^3, a dozen float steps at 1000, so that the scaling is not lost to
// rounding) every fluid density is scaled by S / S0, which puts the sum back to first order and
// leaves the density differences (the pressure gradients) as they were. The same role as the
// reference pressure of an incompressible solver in a closed domain (OpenFOAM's pRefValue), which
// fixes a level the equations leave free; SPHinXsys's internal flows take the summation density
// instead. Not for a free surface, whose fluid's volume may change. CPU backend.
#include <cstdint>
#include <string>

#include "../case/case.hpp"

namespace spate {

class SlabWorker;

class ClosedVolume {
 public:
  static constexpr double kTolerance = 1e-6;  // relative change of S that triggers the scaling

  explicit ClosedVolume(const Case& c) : on_(c.closed_volume) {}
  bool on() const { return on_; }
  // At the start of a run that is not a restart: S0 is the fluid's S now (every slab calls it).
  void start(SlabWorker& w);
  // After a step (every slab calls it): scales the densities when S has left S0 (see above).
  void hold(SlabWorker& w);
  // How often the densities were scaled in this process's run.
  std::int64_t scalings() const { return scalings_; }
  // The state a restart continues from (checkpoint attribute `closed_volume`): S0 in units of 2^-30;
  // empty when off. restore() refuses a text that does not fit the case.
  std::string save() const;
  void restore(const std::string& text);

 private:
  bool on_;
  std::int64_t reference_ = 0;  // S0 in units of 2^-30
  std::int64_t scalings_ = 0;
};

// S = sum over the fluid particles of every slab of rho0 / rho, in units of 2^-30 (exact integer
// sums: the same on every slab and for any split).
std::int64_t fluid_volume_sum(SlabWorker& w);

}  // namespace spate
