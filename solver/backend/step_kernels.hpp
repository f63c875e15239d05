#pragma once
// The arithmetic of one time step on one device, as the slab worker sequences it. With the CPU
// backend the worker owns the host ParticleStore and does everything topological on it
// (migration, the (cell, id) sort, halos: solver/domain, solver/grid); the backend only runs the
// physics loops. A device-resident backend (CUDA) also offers the data-movement primitives of
// SlabArrays, and the worker runs the same topology on its arrays instead (SlabTopology).
#include <cstddef>
#include <stdexcept>
#include <string>

#include "../grid/cell_grid.hpp"
#include "../domain/slab_arrays.hpp"
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
  // Host-store backends: fluid rates of the owned particles in owned cells [first_cell, last_cell)
  // (the worker computes the interior while the halo refresh travels, then the boundary cells).
  // Resident backends use fluid_rates_range instead.
  virtual void fluid_rates_cells(ParticleStore& p, const CellGrid& g, const PhysicsParams& P, std::uint32_t first_cell,
                                 std::uint32_t last_cell) {
    (void)p, (void)g, (void)P, (void)first_cell, (void)last_cell;
    throw std::logic_error(std::string(name()) + " backend: fluid_rates_cells is for host-store backends");
  }
  // Surface tension (only when PhysicsParams::surface_tension.on): the colour gradient of the owned
  // particles, before the halo refresh; the force, after the fluid rates (owned fluid).
  virtual void colour_gradient(ParticleStore& p, const CellGrid& g, const PhysicsParams& P) {
    (void)p, (void)g, (void)P;
    throw std::logic_error(std::string(name()) + " backend: no surface tension");
  }
  virtual void surface_tension(ParticleStore& p, const CellGrid& g, const PhysicsParams& P) {
    (void)p, (void)g, (void)P;
    throw std::logic_error(std::string(name()) + " backend: no surface tension");
  }
  // Particle shifting (only called when P.shifting.enabled): the displacement of the owned fluid
  // particles into `shift`, after the fluid rates and before correct(), which applies it.
  virtual void shifting(ParticleStore& p, const CellGrid& g, const PhysicsParams& P, float dt) {
    (void)p, (void)g, (void)P, (void)dt;
    throw std::logic_error(std::string(name()) + " backend: no particle shifting");
  }
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

  // Device-resident backends keep the particles in their own arrays for the whole run: the worker
  // then runs the topology on those (SlabTopology) and the host store is only a mirror, filled on
  // output steps. nullptr (the CPU backend): the host store is the only copy.
  virtual SlabArrays* resident() { return nullptr; }
  // Resident backends only: fluid rates of owned particles [range.first, range.end()), the
  // interior/boundary split that overlaps the fluid loop with the halo refresh.
  virtual void fluid_rates_range(const CellGrid& g, const PhysicsParams& P, ParticleRange range) {
    (void)g, (void)P, (void)range;
  }
};

}  // namespace spate
