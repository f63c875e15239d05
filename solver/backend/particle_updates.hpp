#pragma once
// The per-particle bodies of the neighbour loops, shared by the OpenMP driver (a loop over cells)
// and the CUDA driver (one thread per particle): particle i in cell g visits its neighbours in the
// fixed (cell, id) order of CellGridView and calls the physics in solver/physics. `Fields` is any
// structure of arrays with ParticleStore's field names (host vectors or device pointers).
#include <cstdint>

#include "../grid/cell_grid_view.hpp"
#include "../particles/particle_access.hpp"
#include "../physics/density_gradient.hpp"
#include "../physics/fluid_interactions.hpp"
#include "../physics/heat_transfer.hpp"
#include "../physics/integrator.hpp"
#include "../physics/multiphase_interactions.hpp"
#include "../physics/surface_tension.hpp"
#include "../physics/shifting.hpp"
#include "../physics/turbulence.hpp"
#include "../physics/wall_boundary.hpp"

namespace spate {

// Heat transfer (physics/heat_transfer.hpp): how particle i's temperature is found, and the face a
// tank particle stands behind.
template <class Fields>
SPATE_HD ThermalCondition particle_temperature_condition(const PhysicsParams& P, const Fields& f, std::uint32_t i, ThermalFace& face) {
  float x[3] = {0.0f, 0.0f, 0.0f};
  for (int k = 0; k < P.dim; ++k) x[k] = f.pos[k][i];
  return temperature_condition(P.heat, f.material[i], P.materials.tank(), P.tank_lo, P.tank_hi, x, P.dim, face);
}

// The integrator's halves for the temperature (as for the density, physics/integrator.hpp, with
// compensated sums) of a particle whose temperature is integrated; the others are set by the wall
// temperature pass or held.
template <class Fields>
SPATE_HD void predict_temperature(const PhysicsParams& P, Fields& f, std::uint32_t i, float dt) {
  ThermalFace face;
  if (particle_temperature_condition(P, f, i, face) == ThermalCondition::Conducting)
    compensated_add(f.temperature[i], f.temperature_residual[i], dt * f.temperature_rate_prev[i]);
}
// With particle shifting, a fluid particle's temperature follows it to its shifted position
// (T += grad T . dr, the first-order correction of delta-plus-SPH for any transported field).
template <class Fields>
SPATE_HD void correct_temperature(const PhysicsParams& P, Fields& f, std::uint32_t i, float dt) {
  ThermalFace face;
  if (particle_temperature_condition(P, f, i, face) != ThermalCondition::Conducting) return;
  compensated_add(f.temperature[i], f.temperature_residual[i], 0.5f * dt * (f.temperature_rate[i] - f.temperature_rate_prev[i]));
  if (P.shifting.enabled && P.is_fluid(f.material[i])) {
    float carried = 0.0f;
    for (int k = 0; k < P.dim; ++k) carried += f.temperature_gradient[k][i] * f.shift[k][i];
    compensated_add(f.temperature[i], f.temperature_residual[i], carried);
  }
}

// The predictor of particle i (physics/integrator.hpp): a fluid particle drifts and kicks with
// the previous rates; a wall particle that follows a motion moves rigidly from t_n to t_n+1
// (physics/wall_motion.hpp); a static wall stays.
template <class Fields>
SPATE_HD void predict_particle(const PhysicsParams& P, Fields& f, std::uint32_t i, float dt) {
  if (P.heat.on) predict_temperature(P, f, i, dt);
  const std::uint8_t m = f.material[i];
  if (!P.is_fluid(m)) {
    const int motion = P.materials.motion[m];
    if (motion > 0) {
      apply_motion_step(P.motion_step[motion - 1], P.dim, f.pos, i);
      // A moving wall that slides carries its surface normal along (WallFrame).
      if (P.materials.face_shear[m] != FaceShear::NoSlip) turn_with_motion_step(P.motion_step[motion - 1], P.dim, f.wall_normal, i);
    }
    return;
  }
  for (int k = 0; k < P.dim; ++k) predict_component(f.pos[k][i], f.vel[k][i], f.acc_prev[k][i], dt);
  if (P.density_mode == DensityMode::Continuity) predict_density(f.density[i], f.density_rate_prev[i], dt);
}

// The viscosity of fluid particle i, and what the multiphase pair terms read of neighbour j's
// fluid: with a temperature table (heat_transfer.hpp), at their own temperatures.
template <class Fields>
SPATE_HD float particle_viscosity(const PhysicsParams& P, const Fields& f, std::uint32_t i) {
  const std::uint8_t m = f.material[i];
  const float mu = P.materials.of(m).viscosity;
  return P.heat.viscosity_varies ? P.heat.viscosity(m, mu, f.temperature[i]) : mu;
}
template <class Fields>
SPATE_HD NeighbourFluid particle_neighbour_fluid(const PhysicsParams& P, const Fields& f, std::uint32_t j) {
  return P.heat.viscosity_varies ? neighbour_fluid(P, f.material[j], f.temperature[j]) : neighbour_fluid(P, f.material[j]);
}

// Neighbour j's pair terms added to `sums` for fluid particle i of material M (viscosity mu_i).
// Multiphase: the pair terms of multiphase_interactions.hpp with each neighbour's own fluid (and
// viscosity: every run with a temperature table takes them, dispatch.hpp). MovingWalls: walls carry
// their prescribed velocity into continuity (ParticleState::w), and free-slip faces slide for the
// artificial viscosity (PairKinematics::vr_av). Riemann: the Riemann options' terms
// (dispatch_pair_flags).
template <class Kernel, int Dim, bool Gamma7, bool Multiphase, bool MovingWalls, bool Riemann, class Fields>
SPATE_HD void add_fluid_neighbour(const PhysicsParams& P, const FluidMaterial& M, const ParticleState<Dim>& si, float mu_i, const Fields& f,
                                  std::uint32_t j, FluidRates<Dim>& sums) {
  ParticleState<Dim> sj = load_state<Dim>(f, j);
  if constexpr (MovingWalls) {
    sj.w = boundary_velocity<Dim>(P, sj);
    sj.w_av = sliding_velocity<Dim>(P, f, j, sj);
  }
  if constexpr (Multiphase) {
    add_pair_rates(sums, multiphase_pair_terms<Kernel, Dim, Gamma7, MovingWalls, Riemann>(P, M, si, sj, particle_neighbour_fluid(P, f, j), mu_i));
  } else {
    (void)mu_i;
    accumulate_fluid_pair<Kernel, Dim, Gamma7, MovingWalls, Riemann>(P, M, si, sj, sums);
  }
}

// Fluid particle i's rates from its neighbour sums: finish_fluid_rates's once-per-particle terms,
// then stored (the density rate only under continuity).
template <int Dim, class Fields>
SPATE_HD void store_fluid_rates(const PhysicsParams& P, const FluidMaterial& M, const ParticleState<Dim>& si, Fields& f, std::uint32_t i,
                                FluidRates<Dim>& rates) {
  finish_fluid_rates(P, M, si, rates);
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) f.acc[k][i] = rates.acc[k];
  f.density_rate[i] = P.density_mode == DensityMode::Continuity ? rates.density_rate : 0.0f;
}

// A wall particle's rates from the fluid pass: none.
template <int Dim, class Fields>
SPATE_HD void zero_fluid_rates(Fields& f, std::uint32_t i) {
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) f.acc[k][i] = 0.0f;
  f.density_rate[i] = 0.0f;
}

// Acceleration and density rate of fluid particle i (zero rates for walls), its neighbours summed
// one after the other (add_fluid_neighbour). The CPU's fluid pass and the GPU's sum them in lanes
// instead (pair_lanes.hpp); this is the GPU's per-thread loop (SPATE_GPU_PAIR_LOOP=thread).
template <class Kernel, int Dim, bool Gamma7, bool Multiphase, bool MovingWalls, bool Riemann, class Fields>
SPATE_HD void update_fluid_rates(const PhysicsParams& P, const CellGridView& v, Fields& f, std::uint32_t i, const int g[3]) {
  if (!P.is_fluid(f.material[i])) {
    zero_fluid_rates<Dim>(f, i);
    return;
  }
  const ParticleState<Dim> si = load_state<Dim>(f, i);
  const FluidMaterial& M = P.materials.of(si.material);
  const float mu_i = Multiphase ? particle_viscosity(P, f, i) : M.viscosity;
  FluidRates<Dim> rates;
  // About 1 in 6 candidates of the 27 cells lies inside the support (3D); skip the others before
  // paying for the pair terms (which would add exactly zero for them).
  v.for_each_neighbour_range(g, [&](std::uint32_t jb, std::uint32_t je) {
    for (std::uint32_t j = jb; j < je; ++j)
      if (distance_squared<Dim>(si.x, f.pos, j) < P.support2)
        add_fluid_neighbour<Kernel, Dim, Gamma7, Multiphase, MovingWalls, Riemann>(P, M, si, mu_i, f, j, rates);
  });
  store_fluid_rates<Dim>(P, M, si, f, i, rates);
}

// Adami pressure, density and no-slip velocity of wall particle w (fluid particles are skipped).
template <class Kernel, int Dim, class Fields>
SPATE_HD void update_wall_state(const PhysicsParams& P, const CellGridView& v, Fields& f, std::uint32_t w, const int g[3]) {
  if (P.is_fluid(f.material[w])) return;
  const Vec<Dim> xw = load_vec<Dim>(f.pos, w);
  WallSums<Dim> sums;
  // Only the fluid inside the support, tested before its state is loaded (the terms beyond it are
  // exactly zero; the CPU's batched pass selects the same neighbours, so the sums are the same).
  v.for_each_neighbour_range(g, [&](std::uint32_t jb, std::uint32_t je) {
    for (std::uint32_t j = jb; j < je; ++j)
      if (P.is_fluid(f.material[j]) && distance_squared<Dim>(xw, f.pos, j) < P.support2)
        accumulate_wall_pair<Kernel, Dim>(P, xw, load_state<Dim>(f, j), sums);
  });
  WallState<Dim> s = finish_wall(P, sums, f.material[w], xw);
  apply_wall_shear<Dim>(P, f, w, xw, sums, s);
  f.pressure[w] = s.p;
  f.density[w] = s.rho;
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) f.vel[k][w] = s.v[k];
}

// Surface tension, pass 1: the colour gradient of fluid particle i (zero for walls), which the
// halo refresh then sends to the ghosts (physics/surface_tension.hpp).
template <class Kernel, int Dim, class Fields>
SPATE_HD void update_colour_gradient(const PhysicsParams& P, const CellGridView& v, Fields& f, std::uint32_t i, const int g[3]) {
  Vec<Dim> grad = zero_vec<Dim>();
  if (P.is_fluid(f.material[i])) {
    const ParticleState<Dim> si = load_state<Dim>(f, i);
    const float volume_i = P.materials.of(si.material).mass / si.rho;
    v.for_each_neighbour_range(g, [&](std::uint32_t jb, std::uint32_t je) {
      for (std::uint32_t j = jb; j < je; ++j)
        if (distance_squared<Dim>(si.x, f.pos, j) < P.support2)
          grad = grad + colour_gradient_term<Kernel, Dim>(P, si, volume_i, load_state<Dim>(f, j));
    });
    SPATE_UNROLL for (int k = 0; k < Dim; ++k) grad[k] /= volume_i;
  }
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) f.colour_gradient[k][i] = grad[k];
}

// Surface tension, pass 2: the curvature of fluid particle i from its neighbours' normals, and
// the force, added to the acceleration of the fluid pass (physics/surface_tension.hpp).
template <class Kernel, int Dim, class Fields>
SPATE_HD void add_surface_tension(const PhysicsParams& P, const CellGridView& v, Fields& f, std::uint32_t i, const int g[3]) {
  if (!P.is_fluid(f.material[i])) return;
  const Vec<Dim> grad_i = load_vec<Dim>(f.colour_gradient, i);
  if (!has_normal<Dim>(P, grad_i)) return;
  const ParticleState<Dim> si = load_state<Dim>(f, i);
  const float inv_len = 1.0f / sqrtf(dot(grad_i, grad_i));
  Vec<Dim> n_i;
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) n_i[k] = grad_i[k] * inv_len;
  DivergenceSums sums;
  v.for_each_neighbour_range(g, [&](std::uint32_t jb, std::uint32_t je) {
    for (std::uint32_t j = jb; j < je; ++j)
      if (distance_squared<Dim>(si.x, f.pos, j) < P.support2)
        accumulate_divergence<Kernel, Dim>(P, si, n_i, load_state<Dim>(f, j), load_vec<Dim>(f.colour_gradient, j), sums);
  });
  const Vec<Dim> a = surface_tension_acceleration<Dim>(P, si, grad_i, sums);
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) f.acc[k][i] += a[k];
}

// Mass-summation density (eq. 5) of fluid particle i, clipped below at rho0 (free surface).
template <class Kernel, int Dim, class Fields>
SPATE_HD void update_summation_density(const PhysicsParams& P, const CellGridView& v, Fields& f, std::uint32_t i,
                                       const int g[3]) {
  if (!P.is_fluid(f.material[i])) return;
  const FluidMaterial& M = P.materials.of(f.material[i]);
  const Vec<Dim> xi = load_vec<Dim>(f.pos, i);
  float rho = 0.0f;
  v.for_each_neighbour_range(g, [&](std::uint32_t jb, std::uint32_t je) {
    for (std::uint32_t j = jb; j < je; ++j) rho += summation_density_term<Kernel, Dim>(P, M, xi, load_vec<Dim>(f.pos, j));
  });
  f.density[i] = rho < M.rho0 ? M.rho0 : rho;
}

// Particle-shifting displacement of fluid particle i for a step dt (shifting.hpp), into `shift`
// (0 for walls, whose slots the volume-consistent density reads); applied to the position by the
// corrector (apply_shift). Run after the fluid rates, before the corrector changes any density, so
// that owned particles and ghosts read the same neighbour state. CarryVelocity
// (`shifting.correct_velocity`): the velocity gradient is summed in the same loop and the
// velocity's change at the shifted position stored in `shift_velocity` (a compile-time flag, so
// that the loop without it is what it was).
template <class Kernel, int Dim, bool CarryVelocity, class Fields>
SPATE_HD void update_shift_with(const PhysicsParams& P, const CellGridView& v, Fields& f, std::uint32_t i, const int g[3], float dt) {
  if (!P.is_fluid(f.material[i])) {
    SPATE_UNROLL for (int k = 0; k < Dim; ++k) f.shift[k][i] = 0.0f;
    return;
  }
  const FluidMaterial& M = P.materials.of(f.material[i]);
  const Vec<Dim> xi = load_vec<Dim>(f.pos, i);
  const float w_dp = Kernel::value(P.dp * P.inv_h, P.kernel_norm);
  ShiftingSums<Dim> sums;
  [[maybe_unused]] VelocityGradient<Dim> grad_v;
  [[maybe_unused]] const ParticleState<Dim> si{xi, CarryVelocity ? load_vec<Dim>(f.vel, i) : zero_vec<Dim>(), 0.0f, 0.0f, f.material[i],
                                               zero_vec<Dim>(), zero_vec<Dim>()};
  v.for_each_neighbour_range(g, [&](std::uint32_t jb, std::uint32_t je) {
    for (std::uint32_t j = jb; j < je; ++j) {
      const ParticleState<Dim> sj{load_vec<Dim>(f.pos, j), CarryVelocity ? load_vec<Dim>(f.vel, j) : zero_vec<Dim>(), f.density[j], 0.0f,
                                  f.material[j], zero_vec<Dim>(), zero_vec<Dim>()};
      accumulate_shifting_pair<Kernel, Dim>(P, M, f.material[i], w_dp, xi, sj, sums);
      if constexpr (CarryVelocity) accumulate_velocity_gradient<Kernel, Dim>(P, si, sj, M.mass / M.rho0, grad_v);
    }
  });
  const Vec<Dim> dr = shifting_displacement<Dim>(P, M, sums, dt);
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) f.shift[k][i] = dr[k];
  if constexpr (CarryVelocity) {
    const Vec<Dim> dv = shift_velocity_change<Dim>(grad_v, dr);
    SPATE_UNROLL for (int k = 0; k < Dim; ++k) f.shift_velocity[k][i] = dv[k];
  }
}
template <class Kernel, int Dim, class Fields>
SPATE_HD void update_shift(const PhysicsParams& P, const CellGridView& v, Fields& f, std::uint32_t i, const int g[3], float dt) {
  if (P.shifting.correct_velocity) update_shift_with<Kernel, Dim, true>(P, v, f, i, g, dt);
  else update_shift_with<Kernel, Dim, false>(P, v, f, i, g, dt);
}

// `shifting.volume_consistent`: the density change of fluid particle i under every particle's
// shift (shifting.hpp), added to its density. Run after update_shift and a halo refresh of `shift`,
// before the corrector moves anyone; reads only positions, shifts and i's own density, so the
// order in which particles are updated does not matter.
template <class Kernel, int Dim, class Fields>
SPATE_HD void update_shift_density(const PhysicsParams& P, const CellGridView& v, Fields& f, std::uint32_t i, const int g[3]) {
  if (!P.is_fluid(f.material[i])) return;
  const FluidMaterial& M = P.materials.of(f.material[i]);
  const Vec<Dim> xi = load_vec<Dim>(f.pos, i);
  const Vec<Dim> dri = load_vec<Dim>(f.shift, i);
  float sum = 0.0f;
  v.for_each_neighbour_range(g, [&](std::uint32_t jb, std::uint32_t je) {
    for (std::uint32_t j = jb; j < je; ++j)
      sum += shift_volume_term<Kernel, Dim>(P, M, xi, dri, load_vec<Dim>(f.pos, j), load_vec<Dim>(f.shift, j));
  });
  f.density[i] += shift_density_change(f.density[i], sum);
}

// Antuono delta-SPH diffusion, pass 1: the renormalised density gradient of fluid particle i (zero
// for walls) into `density_gradient`, which the halo refresh then sends to the ghosts
// (physics/density_gradient.hpp).
template <class Kernel, int Dim, class Fields>
SPATE_HD void update_density_gradient(const PhysicsParams& P, const CellGridView& v, Fields& f, std::uint32_t i, const int g[3]) {
  Vec<Dim> grad = zero_vec<Dim>();
  if (P.is_fluid(f.material[i])) {
    const ParticleState<Dim> si = load_state<Dim>(f, i);
    const FluidMaterial& M = P.materials.of(si.material);
    DensityGradientSums<Dim> sums;
    v.for_each_neighbour_range(g, [&](std::uint32_t jb, std::uint32_t je) {
      for (std::uint32_t j = jb; j < je; ++j) accumulate_density_gradient<Kernel, Dim>(P, M, si, load_state<Dim>(f, j), sums);
    });
    grad = renormalised_gradient<Dim>(sums);
  }
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) f.density_gradient[k][i] = grad[k];
}

// Antuono delta-SPH diffusion, pass 2: the diffusion of fluid particle i from both particles'
// gradients, added to the density rate of the fluid pass.
template <class Kernel, int Dim, class Fields>
SPATE_HD void add_antuono_diffusion(const PhysicsParams& P, const CellGridView& v, Fields& f, std::uint32_t i, const int g[3]) {
  if (!P.is_fluid(f.material[i])) return;
  const ParticleState<Dim> si = load_state<Dim>(f, i);
  const FluidMaterial& M = P.materials.of(si.material);
  const Vec<Dim> grad_i = load_vec<Dim>(f.density_gradient, i);
  float diffusion = 0.0f;
  v.for_each_neighbour_range(g, [&](std::uint32_t jb, std::uint32_t je) {
    for (std::uint32_t j = jb; j < je; ++j)
      diffusion += antuono_diffusion_term<Kernel, Dim>(P, M, si, grad_i, load_state<Dim>(f, j), load_vec<Dim>(f.density_gradient, j));
  });
  f.density_rate[i] += diffusion;
}

// SPS turbulence (physics/turbulence.hpp): particle i's stored T = tau / rho.
template <int Dim, class Fields>
SPATE_HD SpsStress<Dim> load_sps_stress(const Fields& f, std::uint32_t i) {
  SpsStress<Dim> T;
  T.diagonal = load_vec<Dim>(f.sps_stress, i);
  SPATE_UNROLL for (int k = 0; k < Dim * (Dim - 1) / 2; ++k) T.shear[k] = f.sps_shear[k][i];
  return T;
}

// SPS turbulence, pass 1: the SPS stress of fluid particle i (zero for walls) from its velocity
// gradient, into `sps_stress`/`sps_shear` (which the halo refresh then sends to the ghosts) and
// its eddy viscosity. A wall neighbour stands in for i's fluid (its mass), as in the fluid pass.
template <class Kernel, int Dim, class Fields>
SPATE_HD void update_sps_stress(const PhysicsParams& P, const CellGridView& v, Fields& f, std::uint32_t i, const int g[3]) {
  SpsStress<Dim> T;
  float nu_t = 0.0f;
  if (P.is_fluid(f.material[i])) {
    const ParticleState<Dim> si = load_state<Dim>(f, i);
    const float mass_i = P.materials.of(si.material).mass;
    VelocityGradient<Dim> grad;
    v.for_each_neighbour_range(g, [&](std::uint32_t jb, std::uint32_t je) {
      for (std::uint32_t j = jb; j < je; ++j) {
        const ParticleState<Dim> sj = load_state<Dim>(f, j);
        accumulate_velocity_gradient<Kernel, Dim>(P, si, sj, sps_neighbour_mass(P, sj.material, mass_i) / sj.rho, grad);
      }
    });
    T = sps_stress<Dim>(P, grad, si.rho, nu_t);
  }
  store_sps_stress<Dim>(f, i, T, nu_t);
}

// SPS turbulence, pass 2: the divergence of the SPS stress, added to fluid particle i's
// acceleration from the fluid pass; a wall neighbour carries i's own stress (turbulence.hpp).
template <class Kernel, int Dim, class Fields>
SPATE_HD void add_sps_acceleration(const PhysicsParams& P, const CellGridView& v, Fields& f, std::uint32_t i, const int g[3]) {
  const std::uint8_t m = f.material[i];
  if (!P.is_fluid(m)) return;
  const Vec<Dim> xi = load_vec<Dim>(f.pos, i);
  const SpsStress<Dim> Ti = load_sps_stress<Dim>(f, i);
  const float mass_i = P.materials.of(m).mass;
  Vec<Dim> acc = zero_vec<Dim>();
  v.for_each_neighbour_range(g, [&](std::uint32_t jb, std::uint32_t je) {
    for (std::uint32_t j = jb; j < je; ++j) {
      const bool fluid = P.is_fluid(f.material[j]);
      const SpsStress<Dim> Tj = fluid ? load_sps_stress<Dim>(f, j) : Ti;
      acc = acc + sps_pair_acceleration<Kernel, Dim>(P, xi, Ti, load_vec<Dim>(f.pos, j), Tj, sps_neighbour_mass(P, f.material[j], mass_i));
    }
  });
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) f.acc[k][i] += acc[k];
}

// The volume particle j conducts with (physics/heat_transfer.hpp).
template <class Fields>
SPATE_HD float heat_volume(const PhysicsParams& P, const Fields& f, std::uint32_t j) {
  const std::uint8_t m = f.material[j];
  const bool fluid = P.is_fluid(m);
  return heat_volume(fluid, fluid ? P.materials.of(m).mass : 0.0f, f.density[j], P.heat.wall_volume);
}

// Heat transfer, the wall pass over the owned particles: the temperature of wall particle w behind a
// tank face with a condition (heat_transfer.hpp), from the particles around it that carry their own
// temperature (fluids and solids that conduct): the one nearest w's mirror point across the face,
// carried along the face to it by the fitted gradient of its material; and every particle's `conductivity`, the k
// its neighbours' pair terms use (set once here, so that the heat pass need not work out each
// neighbour's face condition per pair). `each(fn)` calls fn(j) for the candidates around w in the
// visiting order (every particle of the 27 cells, or only those that may carry a temperature:
// carries_temperature; the others are skipped here anyway, so both give the same bits).
// A solid carries its temperature when it conducts (k > 0): a solid without thermal properties
// exchanges no heat, and its starting temperature says nothing about the water beside it.
SPATE_HD bool solid_carries_temperature(const PhysicsParams& P, std::uint8_t m) {
  const ThermalMaterial& t = P.heat.material(m);
  return m != P.materials.tank() && t.condition == ThermalCondition::Conducting && t.conductivity > 0.0f;
}
template <class Fields>
SPATE_HD bool carries_temperature(const PhysicsParams& P, const Fields& f, std::uint32_t j) {
  const std::uint8_t m = f.material[j];
  return P.is_fluid(m) || solid_carries_temperature(P, m);
}
// Whether any solid carries its own temperature: if none does, the carriers around a wall particle
// are its fluid neighbours, which the Adami wall state selects anyway (the CPU then mirrors the
// temperatures in its wall state pass).
SPATE_HD bool solids_carry_temperature(const PhysicsParams& P) {
  for (int m = P.materials.tank() + 1; m < P.materials.count; ++m)
    if (solid_carries_temperature(P, static_cast<std::uint8_t>(m))) return true;
  return false;
}
// Whether particle w's temperature comes from its neighbours (it stands behind a tank face with a
// condition): only those need update_wall_temperature's neighbour loops.
template <class Fields>
SPATE_HD bool mirrors_temperature(const PhysicsParams& P, const Fields& f, std::uint32_t w) {
  ThermalFace face;
  const ThermalCondition c = particle_temperature_condition(P, f, w, face);
  return face.axis >= 0 && c != ThermalCondition::Conducting;
}
// The part of the wall pass that needs no neighbours: for a particle whose temperature is not
// mirrored (a fluid, a conducting wall or solid, a held solid) its conductivity, and false; for one
// behind a face with a condition, true (the face and its condition in `face`, `c`).
template <class Fields>
SPATE_HD bool wall_temperature_needs_neighbours(const PhysicsParams& P, Fields& f, std::uint32_t w, ThermalFace& face,
                                                ThermalCondition& c) {
  c = particle_temperature_condition(P, f, w, face);
  if (face.axis >= 0 && c != ThermalCondition::Conducting) return true;
  // Fluids, conducting walls and solids conduct with their own k; a solid held at its temperature
  // with its own, or (none given: -1) with each neighbour's.
  const float k = P.heat.material(f.material[w]).conductivity;
  f.conductivity[w] = c == ThermalCondition::Fixed && !(k > 0.0f) ? -1.0f : k;
  return false;
}
// Wall particle w's mirror point across its face.
template <int Dim, class Fields>
SPATE_HD Vec<Dim> wall_mirror_point(const Fields& f, std::uint32_t w, const ThermalFace& face) {
  Vec<Dim> mirror = load_vec<Dim>(f.pos, w);
  mirror[face.axis] += 2.0f * face.depth * face.into_fluid;
  return mirror;
}
// The weight of carrier j in the fit around a wall particle at squared distance r2: V_j W.
template <class Kernel>
SPATE_HD float fit_weight(const PhysicsParams& P, float volume, float r2) {
  return volume * Kernel::value(sqrtf(r2) * P.inv_h, P.kernel_norm);
}
// The rest, from the fit over the carriers of n's material and n, the carrier nearest the mirror
// point (material: n's; -1 when there is none).
template <int Dim, class Fields>
SPATE_HD void finish_wall_temperature(const PhysicsParams& P, Fields& f, std::uint32_t w, const ThermalFace& face, ThermalCondition c,
                                      const LinearFitSums<Dim>& sums, std::uint32_t n, int material) {
  const HeatParams& H = P.heat;
  if (material < 0) {  // nothing to mirror: a fixed face keeps its temperature
    if (c == ThermalCondition::FaceTemperature) f.temperature[w] = H.face[face.index()].value;
    f.conductivity[w] = 0.0f;
    return;
  }
  // Carried along the face only: across it, the face's condition draws the line from n itself
  // (face_wall_temperature), at n's own distance from the face, kept at 0.2 h at least so that a
  // particle pressed against the face does not turn its noise into a steep line.
  Vec<Dim> along = wall_mirror_point<Dim>(f, w, face) - load_vec<Dim>(f.pos, n);
  along[face.axis] = 0.0f;
  const float t_near = mirror_temperature<Dim>(sums, f.temperature[n], fitted_gradient<Dim>(sums), P.inv_h * along);
  float xn[3] = {0.0f, 0.0f, 0.0f};
  for (int a = 0; a < Dim; ++a) xn[a] = f.pos[a][n];
  const float near_depth = fmaxf(distance_from_face(P.tank_lo, P.tank_hi, face, xn), 0.2f * P.h);
  const float k = H.material(static_cast<std::uint8_t>(material)).conductivity;
  f.temperature[w] = face_wall_temperature(H.face[face.index()], t_near, near_depth, k, face.depth);
  f.conductivity[w] = k;
}
template <class Kernel, int Dim, class Fields, class Each>
SPATE_HD void wall_temperature_over(const PhysicsParams& P, Fields& f, std::uint32_t w, Each&& each) {
  ThermalFace face;
  ThermalCondition c;
  if (!wall_temperature_needs_neighbours(P, f, w, face, c)) return;
  const Vec<Dim> xw = load_vec<Dim>(f.pos, w);
  // The mirror point, and the carrier nearest to it (the first in the visiting order among equals).
  const Vec<Dim> mirror = wall_mirror_point<Dim>(f, w, face);
  float nearest = INFINITY;
  std::uint32_t n = 0;
  int material = -1;
  // The fit over the neighbours of n's material, in the visiting order. In the same loop for the
  // material of the first carrier met (with one fluid and no conducting solid, the only one); again
  // for another, should the nearest be of one.
  LinearFitSums<Dim> sums;
  auto fit = [&](std::uint32_t j, const Vec<Dim>& dx, float r2) {
    sums.add(fit_weight<Kernel>(P, heat_volume(P, f, j), r2), P.inv_h * dx, f.temperature[j]);
  };
  int fitted = -1;
  each([&](std::uint32_t j) {
    if (!carries_temperature(P, f, j)) return;
    const Vec<Dim> dx = load_vec<Dim>(f.pos, j) - xw;
    const float r2_w = dot(dx, dx);
    if (r2_w >= P.support2) return;
    const float r2 = distance_squared<Dim>(mirror, f.pos, j);
    if (r2 < nearest) nearest = r2, n = j, material = f.material[j];
    if (fitted < 0) fitted = f.material[j];
    if (f.material[j] == fitted) fit(j, dx, r2_w);
  });
  if (material >= 0 && material != fitted) {
    sums = LinearFitSums<Dim>{};
    each([&](std::uint32_t j) {
      if (f.material[j] != material) return;
      const Vec<Dim> dx = load_vec<Dim>(f.pos, j) - xw;
      const float r2 = dot(dx, dx);
      if (r2 < P.support2) fit(j, dx, r2);
    });
  }
  finish_wall_temperature<Dim>(P, f, w, face, c, sums, n, material);
}
template <class Kernel, int Dim, class Fields>
SPATE_HD void update_wall_temperature(const PhysicsParams& P, const CellGridView& v, Fields& f, std::uint32_t w, const int g[3]) {
  wall_temperature_over<Kernel, Dim>(P, f, w, [&](auto&& fn) {
    v.for_each_neighbour_range(g, [&](std::uint32_t jb, std::uint32_t je) {
      for (std::uint32_t j = jb; j < je; ++j) fn(j);
    });
  });
}

// Heat transfer: neighbour j's share of rho_i c_i dT_i/dt for particle i (material Mi, at xi, at
// temperature ti) whose temperature is integrated, with the k the wall pass set for j
// (`conductivity`: its own; behind a tank face with a condition the mirrored material's; -1 for a
// held solid without one: i's).
// The pair term from the pair's radial factors (PairKinematics: the CPU's fluid loop passes the
// fluid pair terms' own), j's temperature, k (`conductivity`) and volume (heat_volume), for i of
// conductivity ki at temperature ti.
template <int Dim>
SPATE_HD float conduction_from(const PhysicsParams& P, const PairKinematics<Dim>& pk, float ki, float ti, float tj, float kj, float vj) {
  return conduction_term(P.heat, pk.r2, pk.F, pk.inv_r2_eta, ti, tj, pair_conductivity(ki, kj < 0.0f ? ki : kj), vj);
}
template <class Kernel, int Dim, class Fields>
SPATE_HD float heat_pair_term(const PhysicsParams& P, const Fields& f, const ThermalMaterial& Mi, const Vec<Dim>& xi, float ti, std::uint32_t j) {
  // The radial factors as the fluid pair terms compute them (the positions are all they read), so
  // that this per-particle sum and the CPU's fused one add the same terms.
  const PairKinematics<Dim> pk = radial_kinematics<Kernel, Dim>(P, xi, load_vec<Dim>(f.pos, j));
  return conduction_from<Dim>(P, pk, Mi.conductivity, ti, f.temperature[j], f.conductivity[j], heat_volume(P, f, j));
}

// Heat transfer, after the fluid rates: the conduction rate dT/dt of owned particle i whose
// temperature is integrated (0 for the others), and the Boussinesq buoyancy added to a fluid's
// acceleration (physics/heat_transfer.hpp).
// Particle i's temperature rate from its conduction sum (rho_i c_i dT_i/dt), and a fluid's
// Boussinesq buoyancy added to its acceleration (after the fluid rates have set it).
template <int Dim, class Fields>
SPATE_HD void finish_heat_rates(const PhysicsParams& P, Fields& f, std::uint32_t i, float sum) {
  const std::uint8_t mi = f.material[i];
  const bool fluid_i = P.is_fluid(mi);
  const ThermalMaterial& Mi = P.heat.material(mi);
  const float rho_c = (fluid_i ? f.density[i] : Mi.density) * Mi.specific_heat;
  f.temperature_rate[i] = rho_c > 0.0f ? sum / rho_c : 0.0f;
  if (fluid_i && Mi.expansion != 0.0f) {
    const Vec<Dim> a = buoyancy_acceleration<Dim>(Mi, P.heat.gravity, f.temperature[i]);
    SPATE_UNROLL for (int k = 0; k < Dim; ++k) f.acc[k][i] += a[k];
  }
}

// Heat transfer's conduction sum of a fluid particle runs inside the fluid pass's neighbour loop,
// over the neighbours it selects anyway and in its lane order (the CPU's batched pass,
// fluid_rates_batched with Heat; the GPU's half-warp pass, update_fluid_rates_in_lanes); the heat
// pass is then left with the walls and solids that conduct. Not with particle shifting, whose
// temperature gradient the heat pass computes beside the sum.
SPATE_HD bool fused_heat(const PhysicsParams& P) { return P.heat.on && !P.shifting.enabled; }

template <class Kernel, int Dim, class Fields>
SPATE_HD void update_heat_rates(const PhysicsParams& P, const CellGridView& v, Fields& f, std::uint32_t i, const int g[3]) {
  ThermalFace face;
  if (particle_temperature_condition(P, f, i, face) != ThermalCondition::Conducting) {
    f.temperature_rate[i] = 0.0f;
    return;
  }
  const std::uint8_t mi = f.material[i];
  const bool fluid_i = P.is_fluid(mi);
  const ThermalMaterial& Mi = P.heat.material(mi);
  const Vec<Dim> xi = load_vec<Dim>(f.pos, i);
  const float ti = f.temperature[i];
  float sum = 0.0f;
  // With shifting, also the temperature gradient of a fluid particle (renormalised on the lattice
  // like every SPH gradient, kernels.hpp), for the corrector's T += grad T . dr.
  const bool gradient = fluid_i && P.shifting.enabled;
  Vec<Dim> grad = zero_vec<Dim>();
  v.for_each_neighbour_range(g, [&](std::uint32_t jb, std::uint32_t je) {
    for (std::uint32_t j = jb; j < je; ++j) {
      const float r2 = distance_squared<Dim>(xi, f.pos, j);
      if (r2 >= P.support2) continue;
      sum += heat_pair_term<Kernel, Dim>(P, f, Mi, xi, ti, j);
      if (gradient && P.is_fluid(f.material[j])) {
        const Vec<Dim> xj = load_vec<Dim>(f.pos, j);
        const float vj = P.materials.of(f.material[j]).mass / f.density[j];
        grad = grad + (vj * (f.temperature[j] - ti) * kernel_gradient_factor<Kernel>(P, r2)) * (xi - xj);
      }
    }
  });
  if (gradient) SPATE_UNROLL for (int k = 0; k < Dim; ++k) f.temperature_gradient[k][i] = grad[k];
  finish_heat_rates<Dim>(P, f, i, sum);
}

}  // namespace spate
