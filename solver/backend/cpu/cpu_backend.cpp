#include "cpu_backend.hpp"

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
  const int d = P.dim;
  const bool continuity = P.density_mode == DensityMode::Continuity;
#pragma omp parallel for schedule(static) if (n > kCheapGrain)
  for (std::int64_t i = 0; i < n; ++i) {
    if (!is_fluid(p.kind[i])) continue;
    for (int k = 0; k < d; ++k) predict_component(p.pos[k][i], p.vel[k][i], p.acc_prev[k][i], dt);
    if (continuity) predict_density(p.density[i], p.density_rate_prev[i], dt);
  }
}

void correct(ParticleStore& p, const PhysicsParams& P, float dt) {
  const auto n = static_cast<std::int64_t>(p.owned());
  const int d = P.dim;
  const bool continuity = P.density_mode == DensityMode::Continuity;
#pragma omp parallel for schedule(static) if (n > kCheapGrain)
  for (std::int64_t i = 0; i < n; ++i) {
    if (!is_fluid(p.kind[i])) continue;
    for (int k = 0; k < d; ++k) spate::correct(p.vel[k][i], p.acc[k][i], p.acc_prev[k][i], dt);
    if (continuity) spate::correct(p.density[i], p.density_rate[i], p.density_rate_prev[i], dt);
  }
}

void equation_of_state(ParticleStore& p, const PhysicsParams& P) {
  const auto n = static_cast<std::int64_t>(p.size());
#pragma omp parallel for schedule(static) if (n > kCheapGrain)
  for (std::int64_t i = 0; i < n; ++i)
    if (is_fluid(p.kind[i])) p.pressure[i] = tait_pressure(p.density[i], P.rho0, P.tait_b);
}

void summation_density(ParticleStore& p, const CellGrid& grid, const PhysicsParams& P) {
  dispatch_kernel_dim(P, [&]<class Kernel, int Dim>() {
    const CellGridView v = grid.view();
    for_each_owned_cell(grid, [&](std::uint32_t b, std::uint32_t e, const int g[3]) {
      for (std::uint32_t i = b; i < e; ++i) update_summation_density<Kernel, Dim>(P, v, p, i, g);
    });
  });
}

void wall_state(ParticleStore& p, const CellGrid& grid, const PhysicsParams& P) {
  dispatch_kernel_dim(P, [&]<class Kernel, int Dim>() {
    const CellGridView v = grid.view();
    for_each_owned_cell(grid, [&](std::uint32_t b, std::uint32_t e, const int g[3]) {
      for (std::uint32_t i = b; i < e; ++i) update_wall_state<Kernel, Dim>(P, v, p, i, g);
    });
  });
}

namespace {

// SIMD-friendly fluid rates: the neighbours inside the support are first gathered into contiguous
// per-thread arrays, then the pair terms (the same physics function as everywhere) run over whole
// blocks of kLanes neighbours, neighbour number n (in the fixed visiting order) adding to partial
// sum n mod kLanes; the partial sums are added in lane order at the end. Which lane a neighbour
// lands in depends only on the neighbour sequence, which is the same whatever the split, so results
// stay bit-identical across devices, ranks and threads.
constexpr int kLanes = 16;

template <int Dim>
struct NeighbourBatch {
  std::vector<float> x[Dim], v[Dim], rho, p;
  std::vector<std::uint8_t> kind;
  int n = 0;
  void reserve(int capacity) {
    for (int k = 0; k < Dim; ++k) x[k].resize(capacity), v[k].resize(capacity);
    rho.resize(capacity);
    p.resize(capacity);
    kind.resize(capacity);
  }
};

template <class Kernel, int Dim>
void fluid_rates_batched(ParticleStore& ps, const CellGrid& grid, const PhysicsParams& params) {
  const PhysicsParams P = params;  // a local copy: the vectoriser must see that nothing aliases it
  const CellGridView v = grid.view();
  const auto cells = static_cast<std::int64_t>(grid.owned_cell_count());
  const auto particles = static_cast<std::int64_t>(v.start[cells]);
#pragma omp parallel if (particles > kPairGrain)
  {
    NeighbourBatch<Dim> batch;
    int capacity = 0;
#pragma omp for schedule(dynamic, 64)
    for (std::int64_t c = 0; c < cells; ++c) {
      const std::uint32_t b = v.start[c], e = v.start[c + 1];
      if (b == e) continue;
      int g[3];
      grid.global_coords(static_cast<std::uint32_t>(c), g);
      // Candidates of this cell's neighbourhood bound every particle's neighbour count.
      int candidates = 0;
      v.for_each_neighbour_range(g, [&](std::uint32_t jb, std::uint32_t je) { candidates += static_cast<int>(je - jb); });
      if (candidates > capacity) batch.reserve(capacity = candidates + kLanes);
      for (std::uint32_t i = b; i < e; ++i) {
        if (!is_fluid(ps.kind[i])) {
          SPATE_UNROLL for (int k = 0; k < Dim; ++k) ps.acc[k][i] = 0.0f;
          ps.density_rate[i] = 0.0f;
          continue;
        }
        const ParticleState<Dim> si = load_state<Dim>(ps, i);
        batch.n = 0;
        v.for_each_neighbour_range(g, [&](std::uint32_t jb, std::uint32_t je) {
          for (std::uint32_t j = jb; j < je; ++j) {
            if (distance_squared<Dim>(si.x, ps.pos, j) >= P.support2) continue;
            const int n = batch.n++;
            SPATE_UNROLL for (int k = 0; k < Dim; ++k) batch.x[k][n] = ps.pos[k][j], batch.v[k][n] = ps.vel[k][j];
            batch.rho[n] = ps.density[j];
            batch.p[n] = ps.pressure[j];
            batch.kind[n] = ps.kind[j];
          }
        });
        float acc[Dim][kLanes] = {};
        float drho[kLanes] = {};
        const float* bx[Dim];
        const float* bv[Dim];
        SPATE_UNROLL for (int k = 0; k < Dim; ++k) bx[k] = batch.x[k].data(), bv[k] = batch.v[k].data();
        const float* brho = batch.rho.data();
        const float* bp = batch.p.data();
        const std::uint8_t* bkind = batch.kind.data();
        auto term = [&](int n) {
          Vec<Dim> xj, vj;
          SPATE_UNROLL for (int k = 0; k < Dim; ++k) xj[k] = bx[k][n], vj[k] = bv[k][n];
          return fluid_pair_terms<Kernel, Dim>(P, si, ParticleState<Dim>{xj, vj, brho[n], bp[n], bkind[n]});
        };
        int s = 0;
        for (; s + kLanes <= batch.n; s += kLanes) {
          for (int l = 0; l < kLanes; ++l) {
            const FluidRates<Dim> t = term(s + l);
            SPATE_UNROLL for (int k = 0; k < Dim; ++k) acc[k][l] += t.acc[k];
            drho[l] += t.density_rate;
          }
        }
        for (int l = 0; s + l < batch.n; ++l) {
          const FluidRates<Dim> t = term(s + l);
          SPATE_UNROLL for (int k = 0; k < Dim; ++k) acc[k][l] += t.acc[k];
          drho[l] += t.density_rate;
        }
        FluidRates<Dim> rates;
        for (int l = 0; l < kLanes; ++l) {
          SPATE_UNROLL for (int k = 0; k < Dim; ++k) rates.acc[k] += acc[k][l];
          rates.density_rate += drho[l];
        }
        add_body_forces(P, rates);
        SPATE_UNROLL for (int k = 0; k < Dim; ++k) ps.acc[k][i] = rates.acc[k];
        ps.density_rate[i] = P.density_mode == DensityMode::Continuity ? rates.density_rate : 0.0f;
      }
    }
  }
}

}  // namespace

void fluid_rates(ParticleStore& p, const CellGrid& grid, const PhysicsParams& P) {
  dispatch_kernel_dim(P, [&]<class Kernel, int Dim>() { fluid_rates_batched<Kernel, Dim>(p, grid, P); });
}

float min_time_step(const ParticleStore& p, const PhysicsParams& P, const TimeStepControl& c) {
  float dt = std::numeric_limits<float>::infinity();
  const auto n = static_cast<std::int64_t>(p.owned());
  const int d = P.dim;
#pragma omp parallel for schedule(static) reduction(min : dt) if (n > kCheapGrain)
  for (std::int64_t i = 0; i < n; ++i) {
    if (!is_fluid(p.kind[i])) continue;
    float v2 = 0.0f, a2 = 0.0f;
    for (int k = 0; k < d; ++k) {
      v2 += p.vel[k][i] * p.vel[k][i];
      a2 += p.acc[k][i] * p.acc[k][i];
    }
    dt = std::min(dt, particle_time_step(P, c, std::sqrt(v2), std::sqrt(a2)));
  }
  return std::min(dt, viscous_time_step(P, c));
}

}  // namespace spate::cpu
