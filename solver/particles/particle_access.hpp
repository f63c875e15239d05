#pragma once
// Reading one particle of a host ParticleStore as the physics structs (vectors, ParticleState).
#include "../physics/fluid_interactions.hpp"
#include "particle_store.hpp"

namespace spate {

template <int Dim>
inline Vec<Dim> load_vec(const std::vector<float> (&a)[3], std::size_t i) {
  Vec<Dim> v;
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) v[k] = a[k][i];
  return v;
}

template <int Dim>
inline ParticleState<Dim> load_state(const ParticleStore& p, std::size_t i) {
  return ParticleState<Dim>{load_vec<Dim>(p.pos, i), load_vec<Dim>(p.vel, i), p.density[i], p.pressure[i], p.kind[i]};
}

}  // namespace spate
