#pragma once
// The arithmetic of one time step on one device, as the slab worker sequences it. Every backend
// keeps its particles in SlabArrays (the CPU backend: HostSlabArrays over the worker's own host
// store and grid; CUDA: device memory), and the worker runs one step topology on them
// (SlabTopology: migration, the (cell, id) sort, halos, refreshes); the backend runs the physics
// loops over its arrays.
//
// A new pass is one virtual here, called by the worker as kernels_->pass(particles_, grid_,
// params_). The store and grid it receives are the worker's: on the CPU backend they are the arrays
// themselves (current), on a device backend a mirror (stale; ignore them and use the arrays).
#include <cstddef>
#include <stdexcept>
#include <string>

#include "../grid/cell_grid.hpp"
#include "../domain/slab_arrays.hpp"
#include "../particles/particle_store.hpp"
#include "../physics/params.hpp"
#include "../physics/timestep.hpp"
#include "pass_times.hpp"

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
  // Fluid rates of owned particles [range.first, range.end()): the worker computes the interior
  // while the halo refresh travels, then the boundary ranges (SlabTopology::split()).
  virtual void fluid_rates_range(const CellGrid& g, const PhysicsParams& P, ParticleRange range) = 0;
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
  // Antuono delta-SPH diffusion (only when uses_antuono_diffusion(P), physics/params.hpp; the
  // physics: physics/density_gradient.hpp): the renormalised density gradient of the owned
  // particles, before the halo refresh; the diffusion, after the fluid rates (owned fluid).
  virtual void density_gradient(ParticleStore& p, const CellGrid& g, const PhysicsParams& P) {
    (void)p, (void)g, (void)P;
    throw std::logic_error(std::string(name()) + " backend: no renormalised density diffusion");
  }
  virtual void antuono_diffusion(ParticleStore& p, const CellGrid& g, const PhysicsParams& P) {
    (void)p, (void)g, (void)P;
    throw std::logic_error(std::string(name()) + " backend: no renormalised density diffusion");
  }
  // SPS turbulence (only when P.turbulence.on; physics/turbulence.hpp), after the fluid rates: the
  // SPS stress of the owned particles, then (after a halo refresh) its divergence (owned fluid).
  virtual void sps_stress(ParticleStore& p, const CellGrid& g, const PhysicsParams& P) {
    (void)p, (void)g, (void)P;
    throw std::logic_error(std::string(name()) + " backend: no SPS turbulence");
  }
  virtual void sps_acceleration(ParticleStore& p, const CellGrid& g, const PhysicsParams& P) {
    (void)p, (void)g, (void)P;
    throw std::logic_error(std::string(name()) + " backend: no SPS turbulence");
  }
  // Particle shifting (only called when P.shifting.enabled): the displacement of the owned fluid
  // particles into `shift`, after the fluid rates and before correct(), which applies it.
  virtual void shifting(ParticleStore& p, const CellGrid& g, const PhysicsParams& P, float dt) {
    (void)p, (void)g, (void)P, (void)dt;
    throw std::logic_error(std::string(name()) + " backend: no particle shifting");
  }
  // With P.shifting.volume_consistent, after shifting() and a halo refresh of `shift`: each owned
  // fluid particle's density change under the shifts (particle_updates.hpp update_shift_density).
  virtual void shift_density(ParticleStore& p, const CellGrid& g, const PhysicsParams& P) {
    (void)p, (void)g, (void)P;
    throw std::logic_error(std::string(name()) + " backend: no volume-consistent shifting");
  }
  // Heat transfer (only when P.heat.on; physics/heat_transfer.hpp): the temperatures of the owned
  // wall particles behind tank faces with a condition, after the wall state and before the halo
  // refresh; the conduction rates (and the buoyancy, added to the fluid's acceleration) of the owned
  // particles, after the fluid rates.
  virtual void wall_temperature(ParticleStore& p, const CellGrid& g, const PhysicsParams& P) {
    (void)p, (void)g, (void)P;
    throw std::logic_error(std::string(name()) + " backend: no heat transfer");
  }
  virtual void heat_rates(ParticleStore& p, const CellGrid& g, const PhysicsParams& P) {
    (void)p, (void)g, (void)P;
    throw std::logic_error(std::string(name()) + " backend: no heat transfer");
  }
  virtual float min_time_step(const ParticleStore& p, const PhysicsParams& P, const TimeStepControl& c) = 0;

  // The backend's particles, on which the worker runs the step topology. The worker's host store
  // is brought up to date from them (download) when something on the host reads it.
  virtual SlabArrays& arrays() = 0;
  // Bytes the backend holds for this slab outside the host store (device memory).
  virtual std::size_t device_bytes() const { return 0; }

  // Per-pass times (pass_times.hpp), when the worker times its passes: the stretch from
  // begin_pass to end_pass, added to pass p. Here the host's clock (the pass is done when it
  // returns); a device backend measures on its own timeline. pass_seconds() waits for what it
  // measured and returns the sums so far.
  virtual void begin_pass(Pass) { host_clock_.begin(); }
  virtual void end_pass(Pass p) { host_clock_.end(p, pass_seconds_); }
  virtual PassSeconds pass_seconds() { return pass_seconds_; }

 protected:
  PassSeconds pass_seconds_{};

 private:
  HostPassClock host_clock_;
};

}  // namespace spate
