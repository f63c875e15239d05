#include "cpu_backend.hpp"

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
#pragma omp parallel for schedule(dynamic, 64) if (particles > kPairGrain)
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
#pragma omp parallel for schedule(static) if (n > kCheapGrain)
  for (std::int64_t i = 0; i < n; ++i) predict_particle(P, p, static_cast<std::uint32_t>(i), dt);
}

void correct(ParticleStore& p, const PhysicsParams& P, float dt) {
  const auto n = static_cast<std::int64_t>(p.owned());
  const int d = P.dim;
  const bool continuity = P.density_mode == DensityMode::Continuity;
  const bool shifting = P.shifting.enabled;
  const bool heat = P.heat.on;
#pragma omp parallel for schedule(static) if (n > kCheapGrain)
  for (std::int64_t i = 0; i < n; ++i) {
    if (heat) correct_temperature(P, p, static_cast<std::uint32_t>(i), dt);
    if (!P.is_fluid(p.material[i])) continue;
    for (int k = 0; k < d; ++k) spate::correct(p.vel[k][i], p.acc[k][i], p.acc_prev[k][i], dt);
    if (continuity) correct_density(p.density[i], p.density_rate[i], p.density_rate_prev[i], dt, density_floor(P, p.material[i]));
    if (shifting) for (int k = 0; k < d; ++k) apply_shift(p.pos[k][i], p.shift[k][i]);
  }
}

void equation_of_state(ParticleStore& p, const PhysicsParams& P) {
  const auto n = static_cast<std::int64_t>(p.size());
#pragma omp parallel for schedule(static) if (n > kCheapGrain)
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

// Heat transfer's conduction sum of a fluid particle runs inside the fluid pass's neighbour loop
// (fluid_rates_batched), over the neighbours it has selected anyway; the heat pass is then left
// with the walls and solids that conduct. Not with particle shifting, whose temperature gradient
// the heat pass computes beside the sum.
static bool fused_heat(const PhysicsParams& P) { return P.heat.on && !P.shifting.enabled; }

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

// SIMD-friendly fluid rates. Per cell, the candidates (the particles of the 27 cells around it, in
// the fixed visiting order of CellGridView) are copied once into contiguous per-thread arrays; the
// cell's fluid particles then each run four loops over them:
//  1. |r_ij|^2 of every candidate (vectorised; rounded exactly like the pair terms' dot(r, r)),
//  2. the candidates inside the support, compacted in order into an index list (branch-free: about
//     1 candidate in 7 is inside at h = 1.73 dp, so a branch here mispredicts constantly),
//  3. the shared pair terms over those neighbours (vectorised over neighbours), into per-neighbour
//     arrays,
//  4. neighbour number n (in the visiting order) added to partial sum n mod kLanes, the partial
//     sums added in lane order.
// Which lane a neighbour lands in depends only on the neighbour sequence, which is the same
// whatever the split, so results stay bit-identical across devices, ranks and threads.
constexpr int kLanes = 16;
constexpr int kChunk = 8 * kLanes;

template <int Dim>
struct NeighbourBatch {
  // Candidates of the current cell.
  std::vector<float> x[Dim], v[Dim], v_av[Dim], rho, p, r2;
  std::vector<std::uint8_t> material;
  // Several fluids: each candidate's fluid mass, sound speed and viscosity (NeighbourFluid).
  std::vector<float> mass, c0, viscosity;
  // Heat transfer (fused_heat): each candidate's temperature and conductivity.
  std::vector<float> temperature, conductivity;
  // Neighbours of the current particle: candidate numbers, then the pair terms per neighbour.
  std::vector<std::uint32_t> index;
  std::vector<NeighbourRecord> record;
  int capacity = 0;
  void reserve(int n, bool multiphase = false, bool moving_walls = false, bool heat = false) {
    capacity = n;
    record.resize(n);
    for (int k = 0; k < Dim; ++k) x[k].resize(n), v[k].resize(n);
    if (moving_walls) for (int k = 0; k < Dim; ++k) v_av[k].resize(n);
    rho.resize(n), p.resize(n), r2.resize(n), index.resize(n);
    material.resize(n);
    if (multiphase) mass.resize(n), c0.resize(n), viscosity.resize(n);
    if (heat) temperature.resize(n), conductivity.resize(n);
  }
};

// Neighbour n of a chunk (len of them) added to lane n mod kLanes of (vector, scalar) partial sums.
template <int Dim>
inline void add_lanes(float (&vec)[Dim][kLanes], float (&scalar)[kLanes], const float (&tvec)[Dim][kChunk],
                      const float (&tscalar)[kChunk], int len) {
  int s = 0;
  for (; s + kLanes <= len; s += kLanes) {  // must vectorise: lane-sums
    for (int l = 0; l < kLanes; ++l) {
      SPATE_UNROLL for (int k = 0; k < Dim; ++k) vec[k][l] += tvec[k][s + l];
      scalar[l] += tscalar[s + l];
    }
  }
  for (int l = 0; s + l < len; ++l) {
    SPATE_UNROLL for (int k = 0; k < Dim; ++k) vec[k][l] += tvec[k][s + l];
    scalar[l] += tscalar[s + l];
  }
}
// The same for one scalar.
inline void add_lanes(float (&scalar)[kLanes], const float (&tscalar)[kChunk], int len) {
  int s = 0;
  for (; s + kLanes <= len; s += kLanes)
    for (int l = 0; l < kLanes; ++l) scalar[l] += tscalar[s + l];
  for (int l = 0; s + l < len; ++l) scalar[l] += tscalar[s + l];
}

template <class Kernel, int Dim, bool Gamma7, bool Multiphase, bool MovingWalls, bool Riemann>
void fluid_rates_batched(ParticleStore& ps, const CellGrid& grid, const PhysicsParams& params, ParticleRange range) {
  const PhysicsParams P = params;  // a local copy: the vectoriser must see that nothing aliases it
  const CellGridView v = grid.view();
  // The owned cells holding particles of the range; their candidates are gathered whole, their
  // particles outside the range are left alone.
  const std::uint32_t owned_end = v.start[grid.owned_cell_count()];
  const auto lo = static_cast<std::uint32_t>(std::min<std::size_t>(range.first, owned_end));
  const auto hi = static_cast<std::uint32_t>(std::clamp<std::size_t>(range.end(), lo, owned_end));
  const std::uint32_t* starts = v.start;
  const std::uint32_t* starts_end = v.start + grid.owned_cell_count() + 1;
  const auto first = static_cast<std::int64_t>(std::upper_bound(starts, starts_end, lo) - starts) - 1;
  const auto cells = static_cast<std::int64_t>(std::lower_bound(starts, starts_end, hi) - starts);
  const auto particles = static_cast<std::int64_t>(hi - lo);
  const bool heat = fused_heat(P);
#pragma omp parallel if (particles > kPairGrain)
  {
    NeighbourBatch<Dim> batch;
#pragma omp for schedule(dynamic, 64)
    for (std::int64_t c = std::max<std::int64_t>(first, 0); c < cells; ++c) {
      const std::uint32_t b = std::max(v.start[c], lo), e = std::min(v.start[c + 1], hi);
      if (b >= e) continue;
      bool any_fluid = false;
      for (std::uint32_t i = b; i < e; ++i) {
        if (P.is_fluid(ps.material[i])) {
          any_fluid = true;
          continue;
        }
        SPATE_UNROLL for (int k = 0; k < Dim; ++k) ps.acc[k][i] = 0.0f;
        ps.density_rate[i] = 0.0f;
      }
      if (!any_fluid) continue;
      int g[3];
      grid.global_coords(static_cast<std::uint32_t>(c), g);
      int candidates = 0;
      v.for_each_neighbour_range(g, [&](std::uint32_t jb, std::uint32_t je) { candidates += static_cast<int>(je - jb); });
      if (candidates + kSelectSlack > batch.capacity) batch.reserve(candidates + kSelectSlack, Multiphase, MovingWalls, heat);
      float* cx[Dim];
      SPATE_UNROLL for (int k = 0; k < Dim; ++k) cx[k] = batch.x[k].data();
      float* cr2 = batch.r2.data();
      std::uint8_t* ckind = batch.material.data();
      std::uint32_t* index = batch.index.data();
      NeighbourRecord* record = batch.record.data();
      // Moving walls: what continuity and the artificial viscosity see of each candidate (a wall's
      // prescribed velocity, a free-slip face sliding), once per candidate rather than once per pair.
      float* cw[Dim];
      float* cw_av[Dim];
      SPATE_UNROLL for (int k = 0; k < Dim; ++k) cw[k] = batch.v[k].data(), cw_av[k] = batch.v_av[k].data();
      int m = 0;
      v.for_each_neighbour_range(g, [&](std::uint32_t jb, std::uint32_t je) {
        const int len = static_cast<int>(je - jb);
        SPATE_UNROLL for (int k = 0; k < Dim; ++k) std::copy_n(ps.pos[k].data() + jb, len, cx[k] + m);
        std::copy_n(ps.material.data() + jb, len, ckind + m);
        for (int q = 0; q < len; ++q) fill_record<Dim>(ps, jb + q, record[m + q]);
        if constexpr (MovingWalls)
          for (int q = 0; q < len; ++q) {
            ParticleState<Dim> sj = load_state<Dim>(ps, jb + q);
            sj.w = boundary_velocity<Dim>(P, sj);
            const Vec<Dim> w_av = sliding_velocity<Dim>(P, sj);
            SPATE_UNROLL for (int k = 0; k < Dim; ++k) cw[k][m + q] = sj.w[k], cw_av[k][m + q] = w_av[k];
          }
        if constexpr (Multiphase) {
          for (int q = 0; q < len; ++q) {
            const NeighbourFluid f = particle_neighbour_fluid(P, ps, jb + q);
            batch.mass[m + q] = f.mass, batch.c0[m + q] = f.c0, batch.viscosity[m + q] = f.viscosity;
          }
        }
        if (heat) {
          std::copy_n(ps.temperature.data() + jb, len, batch.temperature.data() + m);
          std::copy_n(ps.conductivity.data() + jb, len, batch.conductivity.data() + m);
        }
        m += len;
      });
      for (std::uint32_t i = b; i < e; ++i) {
        if (!P.is_fluid(ps.material[i])) continue;
        const ParticleState<Dim> si = load_state<Dim>(ps, i);
        const FluidMaterial& M = P.materials.of(si.material);  // into the local P (a copy of M stops GCC vectorising)
        [[maybe_unused]] const float mu_i = Multiphase ? particle_viscosity(P, ps, i) : M.viscosity;
        // 1. Squared distances, summed in the order of distance_squared() and dot().
        candidate_distances<Dim>(si.x, cx, candidates, cr2);
        // 2. In-support candidates, in order.
        const int count = select_inside(cr2, candidates, P.support2, index);
        // 3.-4. In chunks (a multiple of kLanes, so lanes do not depend on the chunking): the
        // neighbours' fields gathered into fixed-size local arrays, the pair terms per neighbour,
        // then neighbour n added to lane n mod kLanes.
        float acc[Dim][kLanes] = {};
        float drho[kLanes] = {};
        // The wall sums for the Riemann wall term (finish_fluid_rates), only when it is on.
        const bool wall_sums = Riemann && P.flux == MomentumFlux::Riemann;
        float wall_gradient[Dim][kLanes] = {};
        float wall_weight[kLanes] = {};
        // Heat transfer: the conduction sum, in lanes like the rest.
        float conduction[kLanes] = {};
        const float ki = heat ? P.heat.material(si.material).conductivity : 0.0f;
        const float ti = heat ? ps.temperature[i] : 0.0f;
        for (int s0 = 0; s0 < count; s0 += kChunk) {
          const int len = std::min(kChunk, count - s0);
          const std::uint32_t* chunk = index + s0;
          alignas(64) float jf[8][kChunk];
          float* const fields[8] = {jf[0], jf[1], jf[2], jf[3], jf[4], jf[5], jf[6], jf[7]};
          gather_records(record, chunk, len, fields);
          std::uint8_t jkind[kChunk];
          gather(ckind, chunk, len, jkind);
          [[maybe_unused]] float jw[Dim][MovingWalls ? kChunk : 1], jw_av[Dim][MovingWalls ? kChunk : 1];
          if constexpr (MovingWalls)
            SPATE_UNROLL for (int k = 0; k < Dim; ++k) gather(cw[k], chunk, len, jw[k]), gather(cw_av[k], chunk, len, jw_av[k]);
          [[maybe_unused]] float jmass[Multiphase ? kChunk : 1], jc0[Multiphase ? kChunk : 1], jmu[Multiphase ? kChunk : 1];
          if constexpr (Multiphase) {
            gather(batch.mass.data(), chunk, len, jmass);
            gather(batch.c0.data(), chunk, len, jc0);
            gather(batch.viscosity.data(), chunk, len, jmu);
          }
          // The pair terms, one neighbour per vector lane. This loop is most of a step's flops and
          // must stay vectorised (GCC's report, checked by scripts/check-vectorisation): nothing
          // in the pair terms may branch, call a function without a vector variant (powf: the
          // gamma != 7 loops stay scalar), or select between per-pair values on a run option
          // (option_factor). A refactor that did the last left it scalar, 1.7x slower (issue 36).
          float tacc[Dim][kChunk], tdrho[kChunk], twall[Dim][kChunk], tweight[kChunk];
          for (int n = 0; n < len; ++n) {  // must vectorise: pair-terms
            ParticleState<Dim> sj;
            SPATE_UNROLL for (int k = 0; k < Dim; ++k) sj.x[k] = jf[kRecX + k][n], sj.v[k] = jf[kRecV + k][n];
            sj.rho = jf[kRecRho][n];
            sj.p = jf[kRecP][n];
            sj.material = jkind[n];
            if constexpr (MovingWalls) SPATE_UNROLL for (int k = 0; k < Dim; ++k) sj.w[k] = jw[k][n], sj.w_av[k] = jw_av[k][n];
            FluidRates<Dim> t;
            if constexpr (Multiphase)
              t = multiphase_pair_terms<Kernel, Dim, Gamma7, MovingWalls, Riemann>(P, M, si, sj, NeighbourFluid{jmass[n], jc0[n], jmu[n]}, mu_i);
            else t = fluid_pair_terms<Kernel, Dim, Gamma7, MovingWalls, Riemann>(P, M, si, sj);
            SPATE_UNROLL for (int k = 0; k < Dim; ++k) tacc[k][n] = t.acc[k];
            tdrho[n] = t.density_rate;
            if constexpr (Riemann) {
              SPATE_UNROLL for (int k = 0; k < Dim; ++k) twall[k][n] = t.wall_gradient[k];
              tweight[n] = t.wall_weight;
            }
          }
          add_lanes<Dim>(acc, drho, tacc, tdrho, len);
          if (wall_sums) add_lanes<Dim>(wall_gradient, wall_weight, twall, tweight, len);
          if (heat) {
            float jt[kChunk], jk[kChunk], theat[kChunk];
            gather(batch.temperature.data(), chunk, len, jt);
            gather(batch.conductivity.data(), chunk, len, jk);
            for (int n = 0; n < len; ++n) {  // must vectorise: heat-terms
              Vec<Dim> xj;
              SPATE_UNROLL for (int k = 0; k < Dim; ++k) xj[k] = jf[kRecX + k][n];
              // heat_volume() from what is gathered: a fluid's m / rho (with one fluid, i's mass),
              // a wall's dp^dim.
              float mj = M.mass;
              if constexpr (Multiphase) mj = jmass[n];
              const float vj = jkind[n] < P.materials.fluids ? mj / jf[kRecRho][n] : P.heat.wall_volume;
              theat[n] = conduction_from<Kernel, Dim>(P, ki, si.x, ti, xj, jt[n], jk[n], vj);
            }
            add_lanes(conduction, theat, len);
          }
        }
        FluidRates<Dim> rates;
        for (int l = 0; l < kLanes; ++l) {
          SPATE_UNROLL for (int k = 0; k < Dim; ++k) rates.acc[k] += acc[k][l], rates.wall_gradient[k] += wall_gradient[k][l];
          rates.density_rate += drho[l];
          rates.wall_weight += wall_weight[l];
        }
        finish_fluid_rates(P, M, si, rates);
        SPATE_UNROLL for (int k = 0; k < Dim; ++k) ps.acc[k][i] = rates.acc[k];
        ps.density_rate[i] = P.density_mode == DensityMode::Continuity ? rates.density_rate : 0.0f;
        if (heat) {
          float sum = 0.0f;
          for (int l = 0; l < kLanes; ++l) sum += conduction[l];
          finish_heat_rates<Dim>(P, ps, i, sum);
        }
      }
    }
  }
}

// Adami wall state, with the same per-cell candidate arrays as the fluid loop, except that only
// fluid candidates are kept (a wall particle sums over fluid alone): most wall cells have no fluid
// within one cell and cost nothing, and the rest scan only the fluid around them. The selected
// neighbours are summed one after the other in the visiting order, exactly as the per-particle
// body update_wall_state() does.
template <class Kernel, int Dim>
void wall_state_batched(ParticleStore& ps, const CellGrid& grid, const PhysicsParams& params) {
  const PhysicsParams P = params;
  const CellGridView v = grid.view();
  const auto cells = static_cast<std::int64_t>(grid.owned_cell_count());
  const auto particles = static_cast<std::int64_t>(v.start[cells]);
#pragma omp parallel if (particles > kPairGrain)
  {
    NeighbourBatch<Dim> batch;
    std::vector<std::uint32_t> fluid;
#pragma omp for schedule(dynamic, 64)
    for (std::int64_t c = 0; c < cells; ++c) {
      const std::uint32_t b = v.start[c], e = v.start[c + 1];
      bool any_wall = false;
      for (std::uint32_t i = b; i < e && !any_wall; ++i) any_wall = !P.is_fluid(ps.material[i]);
      if (!any_wall) continue;
      int g[3];
      grid.global_coords(static_cast<std::uint32_t>(c), g);
      int candidates = 0;
      v.for_each_neighbour_range(g, [&](std::uint32_t jb, std::uint32_t je) { candidates += static_cast<int>(je - jb); });
      if (static_cast<int>(fluid.size()) < candidates) fluid.resize(candidates);
      // The fluid candidates, in visiting order (branch-free, like select_inside).
      int m = 0;
      v.for_each_neighbour_range(g, [&](std::uint32_t jb, std::uint32_t je) {
        for (std::uint32_t j = jb; j < je; ++j) {
          fluid[m] = j;
          m += P.is_fluid(ps.material[j]);
        }
      });
      if (m + kSelectSlack > batch.capacity) batch.reserve(m + kSelectSlack);
      float* cx[Dim];
      float* cv[Dim];
      SPATE_UNROLL for (int k = 0; k < Dim; ++k) {
        cx[k] = batch.x[k].data(), cv[k] = batch.v[k].data();
        gather(ps.pos[k].data(), fluid.data(), m, cx[k]);
        gather(ps.vel[k].data(), fluid.data(), m, cv[k]);
      }
      float* crho = batch.rho.data();
      float* cp = batch.p.data();
      float* cr2 = batch.r2.data();
      std::uint32_t* index = batch.index.data();
      gather(ps.density.data(), fluid.data(), m, crho);
      gather(ps.pressure.data(), fluid.data(), m, cp);
      for (std::uint32_t w = b; w < e; ++w) {
        if (P.is_fluid(ps.material[w])) continue;
        const Vec<Dim> xw = load_vec<Dim>(ps.pos, w);
        candidate_distances<Dim>(xw, cx, m, cr2);
        const int count = select_inside(cr2, m, P.support2, index);
        WallSums<Dim> sums;
        for (int s0 = 0; s0 < count; s0 += kChunk) {
          const int len = std::min(kChunk, count - s0);
          const std::uint32_t* chunk = index + s0;
          float jx[Dim][kChunk], jv[Dim][kChunk], jrho[kChunk], jp[kChunk];
          SPATE_UNROLL for (int k = 0; k < Dim; ++k) gather(cx[k], chunk, len, jx[k]), gather(cv[k], chunk, len, jv[k]);
          gather(crho, chunk, len, jrho);
          gather(cp, chunk, len, jp);
          // Each neighbour's terms, one per vector lane (they must stay vectorised, like the fluid
          // pair terms: scripts/check-vectorisation), then added up in the visiting order.
          float tw[kChunk], tpw[kChunk], trr[Dim][kChunk], tvw[Dim][kChunk];
          for (int n = 0; n < len; ++n) {  // must vectorise: wall-pair-terms
            ParticleState<Dim> sj;
            SPATE_UNROLL for (int k = 0; k < Dim; ++k) sj.x[k] = jx[k][n], sj.v[k] = jv[k][n];
            sj.rho = jrho[n];
            sj.p = jp[n];
            sj.material = 0;  // a fluid (the wall sums do not look at it)
            const WallSums<Dim> t = wall_pair_terms<Kernel, Dim>(P, xw, sj);
            tw[n] = t.w;
            tpw[n] = t.pw;
            SPATE_UNROLL for (int k = 0; k < Dim; ++k) trr[k][n] = t.rho_r_w[k], tvw[k][n] = t.v_w[k];
          }
          for (int n = 0; n < len; ++n) {
            WallSums<Dim> t;
            t.w = tw[n];
            t.pw = tpw[n];
            SPATE_UNROLL for (int k = 0; k < Dim; ++k) t.rho_r_w[k] = trr[k][n], t.v_w[k] = tvw[k][n];
            add_wall_pair(sums, t);
          }
        }
        WallState<Dim> st = finish_wall(P, sums, ps.material[w], xw);
        apply_wall_shear<Dim>(P, xw, ps.material[w], sums, st);
        ps.pressure[w] = st.p;
        ps.density[w] = st.rho;
        SPATE_UNROLL for (int k = 0; k < Dim; ++k) ps.vel[k][w] = st.v[k];
      }
    }
  }
}

}  // namespace

void fluid_rates(ParticleStore& p, const CellGrid& grid, const PhysicsParams& P, ParticleRange range) {
  dispatch_pair_loop(P, [&]<class Kernel, int Dim, bool Gamma7, bool Multiphase, bool MovingWalls, bool Riemann>() {
    fluid_rates_batched<Kernel, Dim, Gamma7, Multiphase, MovingWalls, Riemann>(p, grid, P, range);
  });
}

// Heat transfer's wall pass: every particle's conductivity, and for the particles behind a tank
// face with a condition the neighbour loops of wall_temperature_over over only the candidates
// that may carry a temperature, collected once per cell (as wall_state_batched keeps only the
// fluid; a dry tank cell costs a scan of its own particles), and of those only the ones inside
// the support, selected as the fluid pass selects (vectorised distances, branch-free selection).
// The same candidates in the same order as update_wall_temperature's loops keep (it skips the
// others), so the same bits.
template <class Kernel, int Dim>
void wall_temperature_batched(ParticleStore& ps, const CellGrid& grid, const PhysicsParams& params) {
  const PhysicsParams P = params;
  const CellGridView v = grid.view();
  const auto cells = static_cast<std::int64_t>(grid.owned_cell_count());
  const auto particles = static_cast<std::int64_t>(v.start[cells]);
#pragma omp parallel if (particles > kPairGrain)
  {
    std::vector<std::uint32_t> carriers, inside;
    std::vector<float> cx[Dim], cr2;
#pragma omp for schedule(dynamic, 64)
    for (std::int64_t c = 0; c < cells; ++c) {
      const std::uint32_t b = v.start[c], e = v.start[c + 1];
      bool mirrors = false;
      for (std::uint32_t i = b; i < e && !mirrors; ++i) mirrors = mirrors_temperature(P, ps, i);
      if (!mirrors) {  // conductivities only
        for (std::uint32_t i = b; i < e; ++i) wall_temperature_over<Kernel, Dim>(P, ps, i, [](auto&&) {});
        continue;
      }
      carriers.clear();
      int g[3];
      grid.global_coords(static_cast<std::uint32_t>(c), g);
      v.for_each_neighbour_range(g, [&](std::uint32_t jb, std::uint32_t je) {
        for (std::uint32_t j = jb; j < je; ++j)
          if (carries_temperature(P, ps, j)) carriers.push_back(j);
      });
      const int count = static_cast<int>(carriers.size());
      if (static_cast<int>(cr2.size()) < count + kSelectSlack) {
        for (auto& a : cx) a.resize(count + kSelectSlack);
        cr2.resize(count + kSelectSlack), inside.resize(count + kSelectSlack);
      }
      float* px[Dim];
      SPATE_UNROLL for (int k = 0; k < Dim; ++k) {
        px[k] = cx[k].data();
        for (int q = 0; q < count; ++q) px[k][q] = ps.pos[k][carriers[q]];
      }
      for (std::uint32_t i = b; i < e; ++i) {
        int n = 0;
        if (mirrors_temperature(P, ps, i)) {
          candidate_distances<Dim>(load_vec<Dim>(ps.pos, i), px, count, cr2.data());
          n = select_inside(cr2.data(), count, P.support2, inside.data());
        }
        wall_temperature_over<Kernel, Dim>(P, ps, i, [&](auto&& fn) {
          for (int s = 0; s < n; ++s) fn(carriers[inside[s]]);
        });
      }
    }
  }
}

void wall_state(ParticleStore& p, const CellGrid& grid, const PhysicsParams& P) {
  dispatch_kernel_dim(P, [&]<class Kernel, int Dim>() { wall_state_batched<Kernel, Dim>(p, grid, P); });
}

void wall_temperature(ParticleStore& p, const CellGrid& grid, const PhysicsParams& P) {
  dispatch_kernel_dim(P, [&]<class Kernel, int Dim>() { wall_temperature_batched<Kernel, Dim>(p, grid, P); });
}

void shifting(ParticleStore& p, const CellGrid& grid, const PhysicsParams& P, float dt) {
  per_particle_pass(grid, P, [&]<class Kernel, int Dim>(const CellGridView& v, std::uint32_t i, const int g[3]) {
    update_shift<Kernel, Dim>(P, v, p, i, g, dt);
  });
}

float min_time_step(const ParticleStore& p, const PhysicsParams& P, const TimeStepControl& c) {
  float dt = std::numeric_limits<float>::infinity();
  const auto n = static_cast<std::int64_t>(p.owned());
  const int d = P.dim;
#pragma omp parallel for schedule(static) reduction(min : dt) if (n > kCheapGrain)
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
