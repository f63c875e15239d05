#pragma once
// The arithmetic of one time step on one device, as the slab worker sequences it. The worker owns
// the host ParticleStore and does everything topological on it (migration, the (cell, id) sort,
// halos: solver/domain, solver/grid); a backend only runs the physics loops. A backend whose
// particles live elsewhere (a GPU) is told when the host copy changed and asked for the fields the
// host needs next; for the CPU backend both are no-ops.
#include <cstddef>

#include "../grid/cell_grid.hpp"
#include "../particles/particle_pack.hpp"
#include "../particles/particle_store.hpp"
#include "../physics/params.hpp"
#include "../physics/timestep.hpp"

namespace spate {

class StepKernels {
 public:
  virtual ~StepKernels() = default;
  virtual const char* name() const = 0;

  // The physics loops (see backend/cpu/cpu_backend.hpp for what each computes).
  virtual void predict(ParticleStore& p, const PhysicsParams& P, float dt) = 0;
  virtual void correct(ParticleStore& p, const PhysicsParams& P, float dt) = 0;
  virtual void equation_of_state(ParticleStore& p, const PhysicsParams& P) = 0;
  virtual void summation_density(ParticleStore& p, const CellGrid& g, const PhysicsParams& P) = 0;
  virtual void wall_state(ParticleStore& p, const CellGrid& g, const PhysicsParams& P) = 0;
  virtual void fluid_rates(ParticleStore& p, const CellGrid& g, const PhysicsParams& P) = 0;
  virtual float min_time_step(const ParticleStore& p, const PhysicsParams& P, const TimeStepControl& c) = 0;

  // Residency. `publish`: every field of every particle (owned and ghosts) and the cell table of
  // the host are now the truth (after a rebuild). `publish_fields`: the fields of `set` of
  // particles [first, last) changed on the host (refreshed ghosts). `fetch`: the host needs the
  // fields of `set` of particles [first, last) as the backend last computed them.
  virtual void publish(const ParticleStore&, const CellGrid&) {}
  virtual void publish_fields(const ParticleStore&, FieldSet, std::size_t /*first*/, std::size_t /*last*/) {}
  virtual void fetch(ParticleStore&, FieldSet, std::size_t /*first*/, std::size_t /*last*/) {}
  // Bytes the backend holds for this slab outside the host store (device memory).
  virtual std::size_t device_bytes() const { return 0; }
};

}  // namespace spate
