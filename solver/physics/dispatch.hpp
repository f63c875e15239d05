#pragma once
// Runtime (kernel, dimension) -> compile-time template arguments, in one place for every driver.
#include "params.hpp"

namespace spate {

// Calls f.template operator()<Kernel, Dim>() for the run's kernel and dimension.
template <class F>
void dispatch_kernel_dim(const PhysicsParams& P, F&& f) {
  const bool wendland = P.kernel == KernelType::WendlandC2;
  if (P.dim == 2) {
    if (wendland) f.template operator()<WendlandC2, 2>();
    else f.template operator()<CubicSpline, 2>();
  } else {
    if (wendland) f.template operator()<WendlandC2, 3>();
    else f.template operator()<CubicSpline, 3>();
  }
}

// Whether every fluid of the run has the Tait exponent 7 (the pair terms then use the exact
// product instead of pow).
inline bool all_fluids_gamma7(const PhysicsParams& P) {
  for (int m = 0; m < P.materials.fluids; ++m)
    if (P.materials.fluid[m].gamma != 7.0f) return false;
  return true;
}

// Calls f.template operator()<Fixed..., b...>() with the runtime bools b as template arguments:
// each choice of the bools gets its own compiled loop, and a run pays only for what it uses.
template <bool... Fixed, class F>
void dispatch_flags(F&& f) {
  f.template operator()<Fixed...>();
}
template <bool... Fixed, class F, class... Rest>
void dispatch_flags(F&& f, bool first, Rest... rest) {
  if (first) dispatch_flags<Fixed..., true>(f, rest...);
  else dispatch_flags<Fixed..., false>(f, rest...);
}

// The fluid pair loop's compile-time choices: Gamma7 (every fluid has the Tait exponent 7: the
// exact product instead of pow), Multiphase (several fluids: the interface-consistent pair terms
// of multiphase_interactions.hpp), MovingWalls (some walls move or slide: a moving wall's velocity
// in continuity and the artificial viscosity, a free-slip face's slip in the artificial viscosity;
// PhysicsParams::walls_have_velocity), Riemann (the Riemann options' pair terms and wall sums,
// fluid_interactions.hpp: `density.diffusion: riemann` or `momentum.flux: riemann`). One static
// fluid keeps the single-phase loop, unchanged.
struct PairLoopFlags {
  bool gamma7, multiphase, moving_walls, riemann;
};
inline PairLoopFlags pair_loop_flags(const PhysicsParams& P) {
  // A temperature-dependent viscosity takes the multiphase pair terms, which read each neighbour's.
  return PairLoopFlags{all_fluids_gamma7(P), P.materials.multiphase() || P.heat.viscosity_varies, P.walls_have_velocity(),
                       P.flux == MomentumFlux::Riemann || P.diffusion == DensityDiffusion::Riemann};
}

// f.template operator()<Gamma7, Multiphase, MovingWalls, Riemann>() for `flags`. Only the plain
// loop (one fluid, static no-slip walls) is compiled without the Riemann terms as well: it is the
// one the loads and the benchmarks run, and without them it is about 10% faster (docs/performance.md);
// the other loops always carry them (multiplied by zero when the options are off), which keeps
// the number of compiled loops at 10 per kernel and dimension instead of 16.
template <class F>
void dispatch_pair_flags(const PairLoopFlags& flags, F&& f) {
  if (!flags.riemann && !flags.multiphase && !flags.moving_walls)
    dispatch_flags([&]<bool Gamma7>() { f.template operator()<Gamma7, false, false, false>(); }, flags.gamma7);
  else
    dispatch_flags([&]<bool Gamma7, bool Multiphase, bool MovingWalls>() { f.template operator()<Gamma7, Multiphase, MovingWalls, true>(); },
                   flags.gamma7, flags.multiphase, flags.moving_walls);
}

// As dispatch_kernel_dim, for the fluid pair loop: f.template operator()<Kernel, Dim, Gamma7,
// Multiphase, MovingWalls, Riemann>().
template <class F>
void dispatch_pair_loop(const PhysicsParams& P, F&& f) {
  const PairLoopFlags flags = pair_loop_flags(P);
  dispatch_kernel_dim(P, [&]<class Kernel, int Dim>() {
    dispatch_pair_flags(flags, [&]<bool Gamma7, bool Multiphase, bool MovingWalls, bool Riemann>() {
      f.template operator()<Kernel, Dim, Gamma7, Multiphase, MovingWalls, Riemann>();
    });
  });
}

}  // namespace spate
