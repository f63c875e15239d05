#pragma once
// The OpenMP driver: loops over owned particles (or cells) and calls the shared physics bodies in
// solver/physics. Nothing here knows a formula; it only knows where the arrays are.
#include <limits>

#include "../../domain/slab_plan.hpp"
#include "../../grid/cell_grid.hpp"
#include "../../particles/particle_store.hpp"
#include "../../physics/params.hpp"
#include "../../physics/timestep.hpp"

namespace spate::cpu {

// Integrator halves (physics/integrator.hpp) over owned fluid particles.
void predict(ParticleStore& p, const PhysicsParams& P, float dt);
void correct(ParticleStore& p, const PhysicsParams& P, float dt);
// Tait pressure of every fluid particle, owned and ghost (ghosts carry the owner's density).
void equation_of_state(ParticleStore& p, const PhysicsParams& P);
// Mass summation density (eq. 5) of owned fluid particles, clipped below at rho0 (free surface).
void summation_density(ParticleStore& p, const CellGrid& g, const PhysicsParams& P);
// Adami wall pressure, density and no-slip velocity of owned wall particles.
void wall_state(ParticleStore& p, const CellGrid& g, const PhysicsParams& P);
// Acceleration and density rate of the owned fluid particles [range.first, range.end()) (all by
// default): the cells the range touches are visited, their particles outside it keep their rates.
// Each particle's rates depend only on its own neighbour loop, so a pass split into ranges gives
// the same bits as one pass.
void fluid_rates(ParticleStore& p, const CellGrid& g, const PhysicsParams& P,
                 ParticleRange range = {0, std::numeric_limits<std::size_t>::max()});
// Surface tension (physics/surface_tension.hpp), only when the case has a coefficient: the colour
// gradient of the owned particles (before the halo refresh that carries it to the ghosts), then,
// after the fluid rates, the force added to the owned fluid particles' acceleration.
void colour_gradient(ParticleStore& p, const CellGrid& g, const PhysicsParams& P);
void surface_tension(ParticleStore& p, const CellGrid& g, const PhysicsParams& P);
// Antuono delta-SPH diffusion (physics/density_gradient.hpp), only with `density.diffusion:
// antuono`: the renormalised density gradient of the owned particles (before the halo refresh),
// then, after the fluid rates, the diffusion added to the owned fluid particles' density rate.
void density_gradient(ParticleStore& p, const CellGrid& g, const PhysicsParams& P);
void antuono_diffusion(ParticleStore& p, const CellGrid& g, const PhysicsParams& P);
// SPS turbulence's passes, batched per cell (sps_passes.cpp).
void sps_stress(ParticleStore& p, const CellGrid& g, const PhysicsParams& P);
void sps_acceleration(ParticleStore& p, const CellGrid& g, const PhysicsParams& P);
// Particle-shifting displacement (physics/shifting.hpp) of the owned fluid particles for a step
// dt, into `shift`; correct() then adds it to the positions (only when P.shifting.enabled).
void shifting(ParticleStore& p, const CellGrid& g, const PhysicsParams& P, float dt);
// shifting.volume_consistent: the density change of the owned fluid particles under the shifts,
// after shifting() and a halo refresh of `shift` (physics/shifting.hpp).
void shift_density(ParticleStore& p, const CellGrid& g, const PhysicsParams& P);
// Heat transfer (physics/heat_transfer.hpp), only when P.heat.on: the temperature of the owned wall
// particles behind tank faces with a condition (before the halo refresh), then, after the fluid
// rates, the conduction rates of the owned particles and the buoyancy of the owned fluid.
void wall_temperature(ParticleStore& p, const CellGrid& g, const PhysicsParams& P);
void heat_rates(ParticleStore& p, const CellGrid& g, const PhysicsParams& P);
// Smallest stable time step over owned fluid particles (infinity when there are none).
float min_time_step(const ParticleStore& p, const PhysicsParams& P, const TimeStepControl& c);

// What the CPU code was built for (`spate bench --json`, "cpu"): the widest x86-64 level its
// compile enabled (the compiler's own macros), the widest vectors that level has, and the build's
// instruction-set flags (cmake/SpateWarnings.cmake).
struct BuildTarget {
  const char* isa;
  int vector_bits;
  const char* flags;
};
BuildTarget build_target();

// Whether a run's fluid pair loop is one of the vectorised instantiations (every fluid at
// gamma = 7; scripts/check-vectorisation holds them to it) or a scalar one (another Tait exponent:
// powf per pair).
bool pair_loop_vectorised(const PhysicsParams& P);

}  // namespace spate::cpu

#include "../step_kernels.hpp"
#include "../../domain/host_slab_arrays.hpp"

#include <memory>
#include <utility>

namespace spate::cpu {
// The OpenMP loops behind the StepKernels interface, resident over HostSlabArrays: the worker runs
// the same step topology (SlabTopology: migration, sort, halo, refreshes with the interior /
// boundary overlap) as on a GPU. The arrays are the worker's host store itself, so nothing is
// copied between a "device" and the host; the loops use the arrays' cell table.
class Kernels : public StepKernels {
 public:
  // Over the worker's store (the CPU backend), or over arrays of their own (the tests' stand-in
  // for a device, whose host store is then only a mirror).
  Kernels(ParticleStore& store, CellGrid& grid) : arrays_(std::make_unique<HostSlabArrays>(store, grid)) {}
  explicit Kernels(std::unique_ptr<HostSlabArrays> arrays) : arrays_(std::move(arrays)) {}
  const char* name() const override { return "cpu"; }
  void predict(ParticleStore&, const PhysicsParams& P, float dt) override { cpu::predict(store(), P, dt); }
  void correct(ParticleStore&, const PhysicsParams& P, float dt) override { cpu::correct(store(), P, dt); }
  void equation_of_state(ParticleStore&, const PhysicsParams& P) override { cpu::equation_of_state(store(), P); }
  void summation_density(ParticleStore&, const CellGrid&, const PhysicsParams& P) override {
    cpu::summation_density(store(), arrays_->grid(), P);
  }
  void wall_state(ParticleStore&, const CellGrid&, const PhysicsParams& P) override {
    cpu::wall_state(store(), arrays_->grid(), P);
  }
  void fluid_rates_range(const CellGrid&, const PhysicsParams& P, ParticleRange range) override {
    cpu::fluid_rates(store(), arrays_->grid(), P, range);
  }
  void colour_gradient(ParticleStore&, const CellGrid&, const PhysicsParams& P) override {
    cpu::colour_gradient(store(), arrays_->grid(), P);
  }
  void surface_tension(ParticleStore&, const CellGrid&, const PhysicsParams& P) override {
    cpu::surface_tension(store(), arrays_->grid(), P);
  }
  void density_gradient(ParticleStore&, const CellGrid&, const PhysicsParams& P) override {
    cpu::density_gradient(store(), arrays_->grid(), P);
  }
  void antuono_diffusion(ParticleStore&, const CellGrid&, const PhysicsParams& P) override {
    cpu::antuono_diffusion(store(), arrays_->grid(), P);
  }
  void sps_stress(ParticleStore&, const CellGrid&, const PhysicsParams& P) override {
    cpu::sps_stress(store(), arrays_->grid(), P);
  }
  void sps_acceleration(ParticleStore&, const CellGrid&, const PhysicsParams& P) override {
    cpu::sps_acceleration(store(), arrays_->grid(), P);
  }
  void shifting(ParticleStore&, const CellGrid&, const PhysicsParams& P, float dt) override {
    cpu::shifting(store(), arrays_->grid(), P, dt);
  }
  void shift_density(ParticleStore&, const CellGrid&, const PhysicsParams& P) override {
    cpu::shift_density(store(), arrays_->grid(), P);
  }
  void wall_temperature(ParticleStore&, const CellGrid&, const PhysicsParams& P) override {
    cpu::wall_temperature(store(), arrays_->grid(), P);
  }
  void heat_rates(ParticleStore&, const CellGrid&, const PhysicsParams& P) override {
    cpu::heat_rates(store(), arrays_->grid(), P);
  }
  float min_time_step(const ParticleStore&, const PhysicsParams& P, const TimeStepControl& c) override {
    return cpu::min_time_step(store(), P, c);
  }
  HostSlabArrays& arrays() override { return *arrays_; }

 private:
  ParticleStore& store() { return arrays_->store(); }
  std::unique_ptr<HostSlabArrays> arrays_;
};
}  // namespace spate::cpu
