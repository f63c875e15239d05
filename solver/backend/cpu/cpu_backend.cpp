#include "cpu_backend.hpp"

#include "fluid_pass.hpp"
#include "neighbour_select.hpp"
#include "parallel.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "../../particles/particle_access.hpp"
#include "../particle_updates.hpp"
#include "../../physics/dispatch.hpp"
#include "../../physics/eos.hpp"
#include "../../physics/fluid_interactions.hpp"
#include "../../physics/multiphase_interactions.hpp"
#include "../../physics/integrator.hpp"
#include "../../physics/wall_boundary.hpp"

namespace spate::cpu {

namespace {

// Calls body(i, g) for every owned particle i, g its global cell coordinates, one cell at a time
// (cells are the unit of work: their neighbour ranges are computed once for all their particles).
template <class Body>
void for_each_owned_cell(const CellGrid& grid, Body&& body) {
  const CellGridView v = grid.view();
  const auto cells = static_cast<std::int64_t>(grid.owned_cell_count());
  const auto particles = static_cast<std::int64_t>(v.start[cells]);
#pragma omp parallel for schedule(dynamic, 64) if (particles > pair_grain())
  for (std::int64_t c = 0; c < cells; ++c) {
    const std::uint32_t b = v.start[c], e = v.start[c + 1];
    if (b == e) continue;
    int g[3];
    grid.global_coords(static_cast<std::uint32_t>(c), g);
    body(b, e, g);
  }
}

}  // namespace

void predict(ParticleStore& p, const PhysicsParams& P, float dt) {
  p.swap_rates();  // the rates of step n become the "previous" ones the corrector needs
  const auto n = static_cast<std::int64_t>(p.owned());
#pragma omp parallel for schedule(static) if (n > cheap_grain())
  for (std::int64_t i = 0; i < n; ++i) predict_particle(P, p, static_cast<std::uint32_t>(i), dt);
}

void correct(ParticleStore& p, const PhysicsParams& P, float dt) {
  const auto n = static_cast<std::int64_t>(p.owned());
  const int d = P.dim;
  const bool continuity = P.density_mode == DensityMode::Continuity;
  const bool shifting = P.shifting.enabled;
  const bool carry_velocity = shifting && P.shifting.correct_velocity;
  const bool heat = P.heat.on;
#pragma omp parallel for schedule(static) if (n > cheap_grain())
  for (std::int64_t i = 0; i < n; ++i) {
    if (heat) correct_temperature(P, p, static_cast<std::uint32_t>(i), dt);
    if (!P.is_fluid(p.material[i])) continue;
    for (int k = 0; k < d; ++k) spate::correct(p.vel[k][i], p.acc[k][i], p.acc_prev[k][i], dt);
    if (continuity) correct_density(p.density[i], p.density_rate[i], p.density_rate_prev[i], dt, density_floor(P, p.material[i]));
    if (shifting) for (int k = 0; k < d; ++k) apply_shift(p.pos[k][i], p.shift[k][i]);
    if (carry_velocity) for (int k = 0; k < d; ++k) p.vel[k][i] += p.shift_velocity[k][i];
  }
}

void equation_of_state(ParticleStore& p, const PhysicsParams& P) {
  const auto n = static_cast<std::int64_t>(p.size());
#pragma omp parallel for schedule(static) if (n > cheap_grain())
  for (std::int64_t i = 0; i < n; ++i)
    if (P.is_fluid(p.material[i])) p.pressure[i] = fluid_pressure(P, P.materials.of(p.material[i]), p.density[i]);
}

// Runs one of the shared per-particle bodies (backend/particle_updates.hpp) over every owned
// particle: body.template operator()<Kernel, Dim>(view, i, g).
template <class Body>
void per_particle_pass(const CellGrid& grid, const PhysicsParams& P, Body&& body) {
  dispatch_kernel_dim(P, [&]<class Kernel, int Dim>() {
    const CellGridView v = grid.view();
    for_each_owned_cell(grid, [&](std::uint32_t b, std::uint32_t e, const int g[3]) {
      for (std::uint32_t i = b; i < e; ++i) body.template operator()<Kernel, Dim>(v, i, g);
    });
  });
}

void summation_density(ParticleStore& p, const CellGrid& grid, const PhysicsParams& P) {
  per_particle_pass(grid, P, [&]<class Kernel, int Dim>(const CellGridView& v, std::uint32_t i, const int g[3]) {
    update_summation_density<Kernel, Dim>(P, v, p, i, g);
  });
}

void colour_gradient(ParticleStore& p, const CellGrid& grid, const PhysicsParams& P) {
  per_particle_pass(grid, P, [&]<class Kernel, int Dim>(const CellGridView& v, std::uint32_t i, const int g[3]) {
    update_colour_gradient<Kernel, Dim>(P, v, p, i, g);
  });
}

void surface_tension(ParticleStore& p, const CellGrid& grid, const PhysicsParams& P) {
  per_particle_pass(grid, P, [&]<class Kernel, int Dim>(const CellGridView& v, std::uint32_t i, const int g[3]) {
    add_surface_tension<Kernel, Dim>(P, v, p, i, g);
  });
}

void density_gradient(ParticleStore& p, const CellGrid& grid, const PhysicsParams& P) {
  per_particle_pass(grid, P, [&]<class Kernel, int Dim>(const CellGridView& v, std::uint32_t i, const int g[3]) {
    update_density_gradient<Kernel, Dim>(P, v, p, i, g);
  });
}

void antuono_diffusion(ParticleStore& p, const CellGrid& grid, const PhysicsParams& P) {
  per_particle_pass(grid, P, [&]<class Kernel, int Dim>(const CellGridView& v, std::uint32_t i, const int g[3]) {
    add_antuono_diffusion<Kernel, Dim>(P, v, p, i, g);
  });
}


void heat_rates(ParticleStore& p, const CellGrid& grid, const PhysicsParams& P) {
  const bool fused = fused_heat(P);
  // Nothing left when no wall or solid conducts: their rates stay 0 (update_heat_rates' value).
  if (fused && !P.heat.walls_conduct) return;
  per_particle_pass(grid, P, [&]<class Kernel, int Dim>(const CellGridView& v, std::uint32_t i, const int g[3]) {
    if (fused && P.is_fluid(p.material[i])) return;  // done by the fluid pass
    update_heat_rates<Kernel, Dim>(P, v, p, i, g);
  });
}

namespace {

}  // namespace

void fluid_rates(ParticleStore& p, const CellGrid& grid, const PhysicsParams& P, ParticleRange range) {
  if (fused_heat(P)) return fluid_rates_with_heat(p, grid, P, range);  // heat_passes.cpp
  dispatch_pair_loop(P, [&]<class Kernel, int Dim, bool Gamma7, bool Multiphase, bool MovingWalls, bool Riemann>() {
    fluid_rates_batched<Kernel, Dim, Gamma7, Multiphase, MovingWalls, Riemann, false>(p, grid, P, range);
  });
}

void wall_state(ParticleStore& p, const CellGrid& grid, const PhysicsParams& P) {
  if (wall_state_mirrors_temperature(P)) return wall_state_with_heat(p, grid, P);  // heat_passes.cpp
  dispatch_kernel_dim(P, [&]<class Kernel, int Dim>() { wall_state_batched<Kernel, Dim, false>(p, grid, P); });
}

void shifting(ParticleStore& p, const CellGrid& grid, const PhysicsParams& P, float dt) {
  per_particle_pass(grid, P, [&]<class Kernel, int Dim>(const CellGridView& v, std::uint32_t i, const int g[3]) {
    update_shift<Kernel, Dim>(P, v, p, i, g, dt);
  });
}

void shift_density(ParticleStore& p, const CellGrid& grid, const PhysicsParams& P) {
  per_particle_pass(grid, P, [&]<class Kernel, int Dim>(const CellGridView& v, std::uint32_t i, const int g[3]) {
    update_shift_density<Kernel, Dim>(P, v, p, i, g);
  });
}

float min_time_step(const ParticleStore& p, const PhysicsParams& P, const TimeStepControl& c) {
  float dt = std::numeric_limits<float>::infinity();
  const auto n = static_cast<std::int64_t>(p.owned());
  const int d = P.dim;
#pragma omp parallel for schedule(static) reduction(min : dt) if (n > cheap_grain())
  for (std::int64_t i = 0; i < n; ++i) {
    if (!P.is_fluid(p.material[i])) continue;
    float v2 = 0.0f, a2 = 0.0f;
    for (int k = 0; k < d; ++k) {
      v2 += p.vel[k][i] * p.vel[k][i];
      a2 += p.acc[k][i] * p.acc[k][i];
    }
    dt = std::min(dt, particle_time_step(P, P.materials.of(p.material[i]), c, std::sqrt(v2), std::sqrt(a2)));
  }
  return std::min(dt, state_free_time_step(P, c));
}

BuildTarget build_target() {
#if !defined(SPATE_ARCH_FLAGS)
#define SPATE_ARCH_FLAGS ""
#endif
#if defined(__AVX512F__) && defined(__AVX512BW__) && defined(__AVX512DQ__) && defined(__AVX512VL__)
  return {"x86-64-v4 (AVX-512)", 512, SPATE_ARCH_FLAGS};
#elif defined(__AVX2__) && defined(__FMA__)
  return {"x86-64-v3 (AVX2)", 256, SPATE_ARCH_FLAGS};
#elif defined(__SSE4_2__)
  return {"x86-64-v2 (SSE4.2)", 128, SPATE_ARCH_FLAGS};
#elif defined(__x86_64__)
  return {"x86-64 (SSE2)", 128, SPATE_ARCH_FLAGS};
#else
  return {"not x86-64", 0, SPATE_ARCH_FLAGS};
#endif
}

bool pair_loop_vectorised(const PhysicsParams& P) { return all_fluids_gamma7(P); }

}  // namespace spate::cpu
