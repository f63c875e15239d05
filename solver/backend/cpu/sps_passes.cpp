// SPS turbulence's two passes on the CPU (physics/turbulence.hpp), batched per cell as the fluid
// pass is (fluid_pass.hpp): the candidates of the 27 (2D: 9) cells around a cell are gathered once
// for all the cell's particles; each fluid particle selects those inside the support (select_inside,
// about 1 in 15 in 3D at h = 1.73 dp), gathers what the pass reads of them in chunks, evaluates the
// shared pair terms vectorised over neighbours (velocity_gradient_term, sps_pair_term) and adds
// neighbour n to partial sum n mod kLanes, the partial sums added in lane order. The lanes depend
// only on the neighbour sequence, so results stay bit-identical across devices, ranks and threads;
// the CUDA backend's per-particle bodies (backend/particle_updates.hpp) sum in visiting order, so
// the two backends agree to rounding, as for the fluid pass.
#include <algorithm>
#include <cstdint>
#include <vector>

#include "cpu_backend.hpp"
#include "fluid_pass.hpp"
#include "neighbour_select.hpp"
#include "parallel.hpp"

#include "../../particles/particle_access.hpp"
#include "../../physics/dispatch.hpp"
#include "../particle_updates.hpp"

namespace spate::cpu {

namespace {

// The candidates around one cell, in visiting order, with what both passes read of them.
template <int Dim>
struct SpsCandidates {
  std::vector<std::uint32_t> index, inside;
  std::vector<float> x[Dim], r2;
  void gather(const ParticleStore& ps, const CellGridView& v, const int g[3]) {
    index.clear();
    v.for_each_neighbour_range(g, [&](std::uint32_t jb, std::uint32_t je) {
      for (std::uint32_t j = jb; j < je; ++j) index.push_back(j);
    });
    const std::size_t n = index.size();
    if (r2.size() < n + kSelectSlack) {
      for (auto& a : x) a.resize(n + kSelectSlack);
      r2.resize(n + kSelectSlack), inside.resize(n + kSelectSlack);
    }
    for (int k = 0; k < Dim; ++k)
      for (std::size_t q = 0; q < n; ++q) x[k][q] = ps.pos[k][index[q]];
  }
  // The candidates inside i's support (positions in `index`), in increasing order; their count.
  int select(const PhysicsParams& P, const Vec<Dim>& xi) {
    float* cx[Dim];
    for (int k = 0; k < Dim; ++k) cx[k] = x[k].data();
    const int n = static_cast<int>(index.size());
    candidate_distances<Dim>(xi, cx, n, r2.data());
    return select_inside(r2.data(), n, P.support2, inside.data());
  }
};

// Calls body(cell's candidates, i) for every owned fluid particle i, and wall(i) for the others.
template <int Dim, class Fluid, class Wall>
void for_each_particle_with_candidates(const ParticleStore& ps, const CellGrid& grid, const PhysicsParams& P, Fluid&& fluid,
                                       Wall&& wall) {
  const CellGridView v = grid.view();
  const auto cells = static_cast<std::int64_t>(grid.owned_cell_count());
  const auto particles = static_cast<std::int64_t>(v.start[cells]);
#pragma omp parallel if (particles > pair_grain())
  {
    SpsCandidates<Dim> c;
#pragma omp for schedule(dynamic, 64)
    for (std::int64_t cell = 0; cell < cells; ++cell) {
      const std::uint32_t b = v.start[cell], e = v.start[cell + 1];
      bool any_fluid = false;
      for (std::uint32_t i = b; i < e; ++i) {
        if (P.is_fluid(ps.material[i])) any_fluid = true;
        else wall(i);
      }
      if (!any_fluid) continue;
      int g[3];
      grid.global_coords(static_cast<std::uint32_t>(cell), g);
      c.gather(ps, v, g);
      for (std::uint32_t i = b; i < e; ++i)
        if (P.is_fluid(ps.material[i])) fluid(c, i);
    }
  }
}

// The lane sums of `count` components, in lane order: the sum of each component.
template <int Count>
void sum_lanes(const float (&lanes)[Count][kLanes], float (&out)[Count]) {
  for (int m = 0; m < Count; ++m) {
    out[m] = 0.0f;
    for (int l = 0; l < kLanes; ++l) out[m] += lanes[m][l];
  }
}

template <class Kernel, int Dim>
void sps_stress_batched(ParticleStore& ps, const CellGrid& grid, const PhysicsParams& P) {
  for_each_particle_with_candidates<Dim>(
      ps, grid, P,
      [&](SpsCandidates<Dim>& c, std::uint32_t i) {
        const Vec<Dim> xi = load_vec<Dim>(ps.pos, i), vi = load_vec<Dim>(ps.vel, i);
        const float mass_i = P.materials.of(ps.material[i]).mass;
        const int n = c.select(P, xi);
        float lanes[Dim * Dim][kLanes] = {};
        for (int s0 = 0; s0 < n; s0 += kChunk) {
          const int len = std::min(kChunk, n - s0);
          float jx[Dim][kChunk], jv[Dim][kChunk], jvolume[kChunk];
          for (int q = 0; q < len; ++q) {
            const std::uint32_t j = c.index[c.inside[s0 + q]];
            SPATE_UNROLL for (int k = 0; k < Dim; ++k) jx[k][q] = ps.pos[k][j], jv[k][q] = ps.vel[k][j];
            const std::uint8_t m = ps.material[j];
            jvolume[q] = sps_neighbour_mass(P, m, mass_i) / ps.density[j];
          }
          float t[Dim * Dim][kChunk];
          for (int q = 0; q < len; ++q) {  // the pair terms, vectorised over neighbours
            Vec<Dim> xj, vj;
            SPATE_UNROLL for (int k = 0; k < Dim; ++k) xj[k] = jx[k][q], vj[k] = jv[k][q];
            float term[Dim][Dim];
            velocity_gradient_term<Kernel, Dim>(P, xi, vi, xj, vj, jvolume[q], term);
            SPATE_UNROLL for (int a = 0; a < Dim; ++a) {
              SPATE_UNROLL for (int b = 0; b < Dim; ++b) t[a * Dim + b][q] = term[a][b];
            }
          }
          for (int m = 0; m < Dim * Dim; ++m) add_lanes(lanes[m], t[m], len);
        }
        float sums[Dim * Dim];
        sum_lanes<Dim * Dim>(lanes, sums);
        VelocityGradient<Dim> grad;
        SPATE_UNROLL for (int a = 0; a < Dim; ++a) {
          SPATE_UNROLL for (int b = 0; b < Dim; ++b) grad.g[a][b] = sums[a * Dim + b];
        }
        float nu_t = 0.0f;
        const SpsStress<Dim> T = sps_stress<Dim>(P, grad, ps.density[i], nu_t);
        store_sps_stress<Dim>(ps, i, T, nu_t);
      },
      [&](std::uint32_t i) { store_sps_stress<Dim>(ps, i, SpsStress<Dim>{}, 0.0f); });
}

template <class Kernel, int Dim>
void sps_acceleration_batched(ParticleStore& ps, const CellGrid& grid, const PhysicsParams& P) {
  constexpr int kShear = Dim * (Dim - 1) / 2;
  for_each_particle_with_candidates<Dim>(
      ps, grid, P,
      [&](SpsCandidates<Dim>& c, std::uint32_t i) {
        const Vec<Dim> xi = load_vec<Dim>(ps.pos, i);
        const SpsStress<Dim> Ti = load_sps_stress<Dim>(ps, i);
        const float mass_i = P.materials.of(ps.material[i]).mass;
        const int n = c.select(P, xi);
        float lanes[Dim][kLanes] = {};
        for (int s0 = 0; s0 < n; s0 += kChunk) {
          const int len = std::min(kChunk, n - s0);
          // A wall neighbour carries i's own stress and stands in for i's fluid (turbulence.hpp).
          float jx[Dim][kChunk], jdiag[Dim][kChunk], jshear[kShear][kChunk], jmass[kChunk];
          for (int q = 0; q < len; ++q) {
            const std::uint32_t j = c.index[c.inside[s0 + q]];
            const std::uint8_t m = ps.material[j];
            const bool fluid = P.is_fluid(m);
            SPATE_UNROLL for (int k = 0; k < Dim; ++k) {
              jx[k][q] = ps.pos[k][j];
              jdiag[k][q] = fluid ? ps.sps_stress[k][j] : Ti.diagonal[k];
            }
            SPATE_UNROLL for (int k = 0; k < kShear; ++k) jshear[k][q] = fluid ? ps.sps_shear[k][j] : Ti.shear[k];
            jmass[q] = sps_neighbour_mass(P, m, mass_i);
          }
          float t[Dim][kChunk];
          for (int q = 0; q < len; ++q) {  // the pair terms, vectorised over neighbours
            Vec<Dim> xj;
            SpsStress<Dim> Tj;
            SPATE_UNROLL for (int k = 0; k < Dim; ++k) xj[k] = jx[k][q], Tj.diagonal[k] = jdiag[k][q];
            SPATE_UNROLL for (int k = 0; k < kShear; ++k) Tj.shear[k] = jshear[k][q];
            const Vec<Dim> a = sps_pair_term<Kernel, Dim>(P, xi, Ti, xj, Tj, jmass[q]);
            SPATE_UNROLL for (int k = 0; k < Dim; ++k) t[k][q] = a[k];
          }
          for (int k = 0; k < Dim; ++k) add_lanes(lanes[k], t[k], len);
        }
        float acc[Dim];
        sum_lanes<Dim>(lanes, acc);
        SPATE_UNROLL for (int k = 0; k < Dim; ++k) ps.acc[k][i] += acc[k];
      },
      [](std::uint32_t) {});
}

}  // namespace

void sps_stress(ParticleStore& p, const CellGrid& grid, const PhysicsParams& P) {
  dispatch_kernel_dim(P, [&]<class Kernel, int Dim>() { sps_stress_batched<Kernel, Dim>(p, grid, P); });
}

void sps_acceleration(ParticleStore& p, const CellGrid& grid, const PhysicsParams& P) {
  dispatch_kernel_dim(P, [&]<class Kernel, int Dim>() { sps_acceleration_batched<Kernel, Dim>(p, grid, P); });
}

}  // namespace spate::cpu
