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

}  // namespace spate
