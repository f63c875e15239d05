#pragma once
// The OpenMP driver: loops over owned particles (or cells) and calls the shared physics bodies in
// solver/physics. Nothing here knows a formula; it only knows where the arrays are.
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
// Acceleration and density rate of the owned fluid particles in owned cells [first_cell,
// last_cell) (all by default). Each particle's rates depend only on its own neighbour loop, so a
// pass split into cell ranges gives the same bits as one pass.
void fluid_rates(ParticleStore& p, const CellGrid& g, const PhysicsParams& P, std::uint32_t first_cell = 0,
                 std::uint32_t last_cell = 0xffffffffu);
// Surface tension (physics/surface_tension.hpp), only when the case has a coefficient: the colour
// gradient of the owned particles (before the halo refresh that carries it to the ghosts), then,
// after the fluid rates, the force added to the owned fluid particles' acceleration.
void colour_gradient(ParticleStore& p, const CellGrid& g, const PhysicsParams& P);
void surface_tension(ParticleStore& p, const CellGrid& g, const PhysicsParams& P);
// Particle-shifting displacement (physics/shifting.hpp) of the owned fluid particles for a step
// dt, into `shift`; correct() then adds it to the positions (only when P.shifting.enabled).
void shifting(ParticleStore& p, const CellGrid& g, const PhysicsParams& P, float dt);
// Smallest stable time step over owned fluid particles (infinity when there are none).
float min_time_step(const ParticleStore& p, const PhysicsParams& P, const TimeStepControl& c);

}  // namespace spate::cpu

#include "../step_kernels.hpp"

namespace spate::cpu {
// The OpenMP loops behind the StepKernels interface; the host store is the only copy.
class Kernels final : public StepKernels {
 public:
  const char* name() const override { return "cpu"; }
  void predict(ParticleStore& p, const PhysicsParams& P, float dt) override { cpu::predict(p, P, dt); }
  void correct(ParticleStore& p, const PhysicsParams& P, float dt) override { cpu::correct(p, P, dt); }
  void equation_of_state(ParticleStore& p, const PhysicsParams& P) override { cpu::equation_of_state(p, P); }
  void summation_density(ParticleStore& p, const CellGrid& g, const PhysicsParams& P) override {
    cpu::summation_density(p, g, P);
  }
  void wall_state(ParticleStore& p, const CellGrid& g, const PhysicsParams& P) override { cpu::wall_state(p, g, P); }
  void fluid_rates_cells(ParticleStore& p, const CellGrid& g, const PhysicsParams& P, std::uint32_t first_cell,
                         std::uint32_t last_cell) override {
    cpu::fluid_rates(p, g, P, first_cell, last_cell);
  }
  void colour_gradient(ParticleStore& p, const CellGrid& g, const PhysicsParams& P) override { cpu::colour_gradient(p, g, P); }
  void surface_tension(ParticleStore& p, const CellGrid& g, const PhysicsParams& P) override { cpu::surface_tension(p, g, P); }
  void shifting(ParticleStore& p, const CellGrid& g, const PhysicsParams& P, float dt) override { cpu::shifting(p, g, P, dt); }
  float min_time_step(const ParticleStore& p, const PhysicsParams& P, const TimeStepControl& c) override {
    return cpu::min_time_step(p, P, c);
  }
};
}  // namespace spate::cpu
