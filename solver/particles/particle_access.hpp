#pragma once
// Reading one particle as the physics structs (vectors, ParticleState), from any structure of
// arrays with the field names of ParticleStore: the host store (std::vector fields) or the CUDA
// backend's device fields (raw pointers). One definition for both backends.
#include <cstddef>

#include "../physics/fluid_interactions.hpp"

namespace spate {

template <int Dim, class Array>
SPATE_HD Vec<Dim> load_vec(const Array (&a)[3], std::size_t i) {
  Vec<Dim> v;
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) v[k] = a[k][i];
  return v;
}

template <int Dim, class Fields>
SPATE_HD ParticleState<Dim> load_state(const Fields& f, std::size_t i) {
  ParticleState<Dim> s;
  s.x = load_vec<Dim>(f.pos, i);
  s.v = load_vec<Dim>(f.vel, i);
  s.rho = f.density[i];
  s.p = f.pressure[i];
  s.material = f.material[i];
  return s;
}

// |x_i - x_j|^2 with x_j read from structure-of-arrays positions: the support test of the pair
// loops, rounded exactly like dot(r, r) in the pair terms.
template <int Dim, class Array>
SPATE_HD float distance_squared(const Vec<Dim>& xi, const Array (&pos)[3], std::size_t j) {
  float r2 = 0.0f;
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) {
    const float d = xi[k] - pos[k][j];
    r2 += d * d;
  }
  return r2;
}

}  // namespace spate
