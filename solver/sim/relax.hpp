#pragma once
// Particle relaxation before t = 0 (the case's `relax:` section; docs/physics.md, "Relaxation"):
// the lattice start, perturbed by a deterministic random offset of each fluid particle, is relaxed
// by repeated particle shifting (physics/shifting.hpp: particles move from where they crowd to where
// they are sparse, a free surface holds, an interface is crossed by nobody, walls stay) into a
// settled, isotropic distribution, as users of other SPH codes do before a case (SPHinXsys'
// relaxation, DualSPHysics' packing). Positions change, nothing else: each particle keeps the
// density of its lattice site (its hydrostatic start, off by rho g |dr| after moving by dr).
#include "../case/case.hpp"
#include "../particles/particle_store.hpp"

namespace spate {

// The relaxed copy of `start` (ids 0..n-1 in generation order, as generate_particles makes them);
// `start` itself when the case does not ask for relaxation. Deterministic, and the same whatever
// the run's split: it runs before the particles are shared out, on one slab of the CPU backend.
ParticleStore relax_particles(const Case& c, const ParticleStore& start);

}  // namespace spate
