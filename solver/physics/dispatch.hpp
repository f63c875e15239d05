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

// As dispatch_kernel_dim, for the fluid pair loop: f.template operator()<Kernel, Dim, Gamma7,
// Multiphase>(). Multiphase (several fluids) selects the interface-consistent pair terms
// (multiphase_interactions.hpp); one fluid keeps the single-phase loop, unchanged.
template <class F>
void dispatch_pair_loop(const PhysicsParams& P, F&& f) {
  const bool gamma7 = all_fluids_gamma7(P);
  const bool multiphase = P.materials.multiphase();
  dispatch_kernel_dim(P, [&]<class Kernel, int Dim>() {
    if (multiphase) {
      if (gamma7) f.template operator()<Kernel, Dim, true, true>();
      else f.template operator()<Kernel, Dim, false, true>();
    } else {
      if (gamma7) f.template operator()<Kernel, Dim, true, false>();
      else f.template operator()<Kernel, Dim, false, false>();
    }
  });
}

}  // namespace spate
