#include "relax.hpp"

#include <cmath>
#include <cstdint>

#include "../case/generator.hpp"
#include "../comm/in_process_transport.hpp"
#include "../domain/particle_checks.hpp"
#include "slab_worker.hpp"

namespace spate {

namespace {

// A uniform number in [-1/2, 1/2) from a particle's id and an axis (splitmix64): the same on every
// machine and rank.
double offset(std::uint32_t id, int axis) {
  std::uint64_t z = (static_cast<std::uint64_t>(id) << 2 | static_cast<std::uint64_t>(axis)) + 0x9e3779b97f4a7c15ull;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  z ^= z >> 31;
  return static_cast<double>(z >> 11) / 9007199254740992.0 - 0.5;  // 53 bits
}

}  // namespace

ParticleStore relax_particles(const Case& c, const ParticleStore& start) {
  if (c.relax_steps <= 0) return start;
  // The shifting pass, its scale set so that each iteration moves a particle by
  // dr = -kappa h^2 sum_j grad_i W_ij V_j (shifting.hpp with C Ma c0 dt = kappa h / 4, R = 0).
  PhysicsParams P = physics_params(c);
  P.shifting.enabled = true;
  P.shifting.coefficient = 1.0f;
  P.shifting.mach = 1.0f;
  // No tensile term: relaxed, sum_j V_j grad W_ij = 0, where eq. 7's p_i + p_j exerts no force on a
  // uniform pressure (with the term the particles settle where it does, and start moving at t = 0).
  P.shifting.tensile = 0.0f;
  for (int k = 0; k < P.materials.fluids; ++k) P.materials.fluid[k].c0 = 1.0f;
  const float dt = static_cast<float>(c.relax_rate) * P.h / 4.0f;

  ParticleStore p = start;
  const int d = c.dim;
  for (std::size_t i = 0; i < p.size(); ++i)
    if (P.is_fluid(p.material[i]))
      for (int a = 0; a < d; ++a) p.pos[a][i] = static_cast<float>(p.pos[a][i] + c.relax_perturbation * c.dp * offset(p.id[i], a));

  const OptionalFields shift_field(true);  // the worker's store carries `shift`
  const Lattice L = make_lattice(c);
  InProcessHub hub(1);
  auto transport = hub.endpoint(0, c.periodic[0]);
  SlabWorker w(L, P, *transport);
  w.take_share(p, SlabLayout::uniform(L.cells[0], 1));
  for (int k = 0; k < c.relax_steps; ++k) w.relax_step(dt);
  const ParticleStore& r = w.particles();
  for (std::size_t i = 0; i < r.owned(); ++i)
    for (int a = 0; a < d; ++a) p.pos[a][r.id[i]] = r.pos[a][i];
  return p;
}

}  // namespace spate
