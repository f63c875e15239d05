#pragma once
// The CPU backend's neighbour passes over fluid and walls (fluid_rates_batched, wall_state_batched),
// a header so that their instantiations with heat transfer compile in a translation unit of their
// own (heat_passes.cpp), beside cpu_backend.cpp's without: the two are the longest compiles, and
// cpu_backend.cpp keeps the inlining it had without them (with the heat instantiations in it, the
// passes without heat took 4% more instructions: callgrind, AVX2 build).
#include <algorithm>
#include <cstdint>
#include <vector>

#include "cpu_backend.hpp"
#include "neighbour_select.hpp"
#include "parallel.hpp"
#include "../../grid/cell_grid.hpp"
#include "../../particles/particle_access.hpp"
#include "../pair_lanes.hpp"
#include "../particle_updates.hpp"
#include "../../physics/fluid_interactions.hpp"
#include "../../physics/multiphase_interactions.hpp"
#include "../../physics/wall_boundary.hpp"

namespace spate::cpu {

// Whether the wall state pass mirrors the temperatures behind the tank faces (wall_state_batched
// with Heat): heat transfer without a solid that carries its own temperature.
inline bool wall_state_mirrors_temperature(const PhysicsParams& P) { return P.heat.on && !solids_carry_temperature(P); }

// The passes with heat transfer (heat_passes.cpp): the fluid pass with the fused conduction sum,
// the wall state pass with the mirrored temperatures.
void fluid_rates_with_heat(ParticleStore& p, const CellGrid& grid, const PhysicsParams& P, ParticleRange range);
void wall_state_with_heat(ParticleStore& p, const CellGrid& grid, const PhysicsParams& P);

// Internal to each translation unit that includes it, as the pass was when it lived in
// cpu_backend.cpp: with external linkage GCC kept the candidate copy and gather_records out of
// line in the pass without heat, 6% more instructions per step (callgrind, AVX2 build).
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
// whatever the split, so results stay bit-identical across devices, ranks and threads; the GPU's
// half-warp pass sums in the same lanes (pair_lanes.hpp), so it gives the same bits as this one.
constexpr int kLanes = kPairLanes;
constexpr int kChunk = 8 * kLanes;

template <int Dim>
struct NeighbourBatch {
  // Candidates of the current cell.
  std::vector<float> x[Dim], v[Dim], v_av[Dim], rho, p, r2;
  std::vector<std::uint8_t> material;
  // Several fluids: each candidate's fluid mass, sound speed and viscosity (NeighbourFluid).
  std::vector<float> mass, c0, viscosity;
  // Heat transfer: each candidate's temperature and conductivity side by side (fused_heat), or
  // temperature and volume (the wall state pass's mirrored temperatures).
  std::vector<FieldPair> heat_pair;
  std::vector<float> temperature, volume;
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
    if (heat) heat_pair.resize(n), temperature.resize(n), volume.resize(n);
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
// The same for F scalars at once (one loop, one tail, rather than one call per field).
template <int F>
inline void add_lanes(float (&lanes)[F][kLanes], const float (&terms)[F][kChunk], int len) {
  int s = 0;
  for (; s + kLanes <= len; s += kLanes)
    for (int f = 0; f < F; ++f)
      for (int l = 0; l < kLanes; ++l) lanes[f][l] += terms[f][s + l];
  for (int l = 0; s + l < len; ++l)
    for (int f = 0; f < F; ++f) lanes[f][l] += terms[f][s + l];
}

// Heat transfer's linear fit of the temperature around a wall particle behind a face
// (LinearFitSums, heat_transfer.hpp) summed in lanes like the fluid sums: neighbour n's terms into
// lane n mod kLanes of each field, the lanes added in lane order at the end (the same bits for any
// split); beside them the range of the neighbours' temperatures and the neighbour nearest the
// wall's mirror point (the first in the visiting order among equals, as wall_temperature_over).
template <int Dim>
struct FitLanes {
  static constexpr int kFields = LinearFitSums<Dim>::kTerms;  // w, wt, wx, wtx, wxx
  using Terms = float[kFields][kChunk];
  float lane[kFields][kLanes];
  float lowest, highest, nearest;
  int near;  // the neighbour's number in the selection (-1: none)
  void reset() {
    for (auto& f : lane)
      for (float& l : f) l = 0.0f;
    lowest = INFINITY, highest = -INFINITY, nearest = INFINITY, near = -1;
  }
  // Neighbour s's terms (LinearFitSums::terms): weight vw = V_j W_ij, temperature t, offset
  // dx = (x_j - x_w) / h. Inside the vectorised loops.
  static void terms(Terms& out, int s, float vw, float t, const float (&dx)[Dim]) {
    LinearFitSums<Dim>::terms(vw, t, dx, [&](int k, float v) { out[k][s] = v; });
  }
  // Neighbour n's offset dx = (x_j - x_w) / h and its squared distance to the mirror point
  // (distance_squared's rounding), from a chunk's gathered positions. Inside the vectorised loops.
  static float offsets(const float (&jx)[Dim][kChunk], int n, const Vec<Dim>& xw, const Vec<Dim>& mirror, float inv_h, float (&dx)[Dim]) {
    float m2 = 0.0f;
    SPATE_UNROLL for (int k = 0; k < Dim; ++k) {
      dx[k] = inv_h * (jx[k][n] - xw[k]);
      const float d = mirror[k] - jx[k][n];
      m2 += d * d;
    }
    return m2;
  }
  // A chunk of len neighbours from number s0 on: their terms, temperatures t and squared distances
  // to the mirror point m2. The minima and maxima do not depend on the order (vectorised); the
  // nearest is then found in order.
  void add(const Terms& out, const float* t, const float* m2, int len, int s0) {
    add_lanes<kFields>(lane, out, len);
    float lo = lowest, hi = highest, chunk_nearest = INFINITY;
    for (int s = 0; s < len; ++s) {
      lo = t[s] < lo ? t[s] : lo;
      hi = t[s] > hi ? t[s] : hi;
      chunk_nearest = m2[s] < chunk_nearest ? m2[s] : chunk_nearest;
    }
    lowest = lo, highest = hi;
    if (chunk_nearest < nearest) {
      nearest = chunk_nearest;
      int s = 0;
      while (m2[s] != chunk_nearest) ++s;
      near = s0 + s;
    }
  }
  LinearFitSums<Dim> sums() const {
    LinearFitSums<Dim> s;
    s.lowest = lowest, s.highest = highest;
    for (int l = 0; l < kLanes; ++l)
      SPATE_UNROLL for (int k = 0; k < kFields; ++k) s.term(k) += lane[k][l];
    return s;
  }
};

// Heat: the fused conduction sum (fused_heat), in the pair terms' loop, from their radial factors.
template <class Kernel, int Dim, bool Gamma7, bool Multiphase, bool MovingWalls, bool Riemann, bool Heat>
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
#pragma omp parallel if (particles > pair_grain())
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
      if (candidates + kSelectSlack > batch.capacity) batch.reserve(candidates + kSelectSlack, Multiphase, MovingWalls, Heat);
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
            const Vec<Dim> w_av = sliding_velocity<Dim>(P, ps, jb + q, sj);
            SPATE_UNROLL for (int k = 0; k < Dim; ++k) cw[k][m + q] = sj.w[k], cw_av[k][m + q] = w_av[k];
          }
        if constexpr (Multiphase) {
          for (int q = 0; q < len; ++q) {
            const NeighbourFluid f = particle_neighbour_fluid(P, ps, jb + q);
            batch.mass[m + q] = f.mass, batch.c0[m + q] = f.c0, batch.viscosity[m + q] = f.viscosity;
          }
        }
        if constexpr (Heat)
          for (int q = 0; q < len; ++q) batch.heat_pair[m + q] = FieldPair{ps.temperature[jb + q], ps.conductivity[jb + q]};
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
        [[maybe_unused]] const float ki = Heat ? P.heat.material(si.material).conductivity : 0.0f;
        [[maybe_unused]] const float ti = Heat ? ps.temperature[i] : 0.0f;
        [[maybe_unused]] const float wall_volume = P.heat.wall_volume;
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
          [[maybe_unused]] float jt[Heat ? kChunk : 1], jk[Heat ? kChunk : 1];
          if constexpr (Heat) gather_pairs(batch.heat_pair.data(), chunk, len, jt, jk);
          // The pair terms, one neighbour per vector lane. This loop is most of a step's flops and
          // must stay vectorised (GCC's report, checked by scripts/check-vectorisation): nothing
          // in the pair terms may branch, call a function without a vector variant (powf: the
          // gamma != 7 loops stay scalar), or select between per-pair values on a run option
          // (option_factor). A refactor that did the last left it scalar, 1.7x slower (issue 36).
          float tacc[Dim][kChunk], tdrho[kChunk], twall[Dim][kChunk], tweight[kChunk];
          [[maybe_unused]] float theat[Heat ? kChunk : 1];
          for (int n = 0; n < len; ++n) {  // must vectorise: pair-terms
            ParticleState<Dim> sj;
            SPATE_UNROLL for (int k = 0; k < Dim; ++k) sj.x[k] = jf[kRecX + k][n], sj.v[k] = jf[kRecV + k][n];
            sj.rho = jf[kRecRho][n];
            sj.p = jf[kRecP][n];
            sj.material = jkind[n];
            if constexpr (MovingWalls) SPATE_UNROLL for (int k = 0; k < Dim; ++k) sj.w[k] = jw[k][n], sj.w_av[k] = jw_av[k][n];
            const PairKinematics<Dim> pk = pair_kinematics<Kernel, Dim, MovingWalls>(P, si, sj);
            FluidRates<Dim> t;
            if constexpr (Multiphase)
              t = multiphase_pair_terms<Kernel, Dim, Gamma7, MovingWalls, Riemann>(P, M, si, sj, NeighbourFluid{jmass[n], jc0[n], jmu[n]}, mu_i, pk);
            else t = fluid_pair_terms<Kernel, Dim, Gamma7, MovingWalls, Riemann>(P, M, si, sj, pk);
            if constexpr (Heat) {
              // heat_volume() from what is gathered (with one fluid, i's mass is j's).
              float mj = M.mass;
              if constexpr (Multiphase) mj = jmass[n];
              const float vj = heat_volume(jkind[n] < P.materials.fluids, mj, sj.rho, wall_volume);
              theat[n] = conduction_from<Dim>(P, pk, ki, ti, jt[n], jk[n], vj);
            }
            SPATE_UNROLL for (int k = 0; k < Dim; ++k) tacc[k][n] = t.acc[k];
            tdrho[n] = t.density_rate;
            if constexpr (Riemann) {
              SPATE_UNROLL for (int k = 0; k < Dim; ++k) twall[k][n] = t.wall_gradient[k];
              tweight[n] = t.wall_weight;
            }
          }
          add_lanes<Dim>(acc, drho, tacc, tdrho, len);
          if (wall_sums) add_lanes<Dim>(wall_gradient, wall_weight, twall, tweight, len);
          if constexpr (Heat) add_lanes(conduction, theat, len);
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
        if constexpr (Heat) {
          float sum = 0.0f;
          for (int l = 0; l < kLanes; ++l) sum += conduction[l];
          finish_heat_rates<Dim>(P, ps, i, sum);
        }
      }
    }
  }
}

// Heat transfer's wall temperature of particle w behind a face with a condition, from the n
// carriers inside its support that the caller has selected: inside[s] numbers a candidate of the
// cell's arrays (positions cx, squared distances to w cr2, temperatures ct, volumes cv, materials
// cm), which is particle carrier[inside[s]]. When they are all of one material (one fluid and no
// conducting solid: the usual case) the fit's terms are computed one neighbour per vector lane and
// added in lanes, neighbour n into lane n mod kLanes, like the fluid pass's sums (the same bits for
// any split); otherwise wall_temperature_over's loops run over them, as on the GPU.
struct CarrierArrays {
  const float* const* x;
  const float *r2, *t, *volume;
  const std::uint8_t* material;
  const std::uint32_t* carrier;
};
template <class Kernel, int Dim>
void wall_temperature_from(const PhysicsParams& P, ParticleStore& ps, std::uint32_t w, const ThermalFace& face,
                           ThermalCondition condition, const CarrierArrays& c, const std::uint32_t* inside, int n);

// Adami wall state, with the same per-cell candidate arrays as the fluid loop, except that only
// fluid candidates are kept (a wall particle sums over fluid alone): most wall cells have no fluid
// within one cell and cost nothing, and the rest scan only the fluid around them. The selected
// neighbours are summed one after the other in the visiting order, exactly as the per-particle
// body update_wall_state() does.
// Heat (heat transfer without solids that carry their own temperature): the carriers around a
// wall particle are the fluid it selects, so the temperatures behind the tank faces are mirrored
// here from the same selection; wall_temperature() then only sets the other particles'
// conductivities. When the cell's fluid candidates are all of one material (one fluid: the usual
// case) the fit's terms are computed in the wall terms' own loop, from its kernel values and
// gathered positions and densities (FitLanes); otherwise wall_temperature_from runs after it.
template <class Kernel, int Dim, bool Heat>
void wall_state_batched(ParticleStore& ps, const CellGrid& grid, const PhysicsParams& params) {
  const PhysicsParams P = params;
  const CellGridView v = grid.view();
  const auto cells = static_cast<std::int64_t>(grid.owned_cell_count());
  const auto particles = static_cast<std::int64_t>(v.start[cells]);
#pragma omp parallel if (particles > pair_grain())
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
      if (m + kSelectSlack > batch.capacity) batch.reserve(m + kSelectSlack, false, false, Heat);
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
      [[maybe_unused]] CarrierArrays carriers{};
      [[maybe_unused]] bool one_material = true;
      [[maybe_unused]] float fit_mass = 0.0f;  // one material: its particles' mass (heat_volume)
      if constexpr (Heat) {
        for (int q = 0; q < m; ++q) {
          const std::uint32_t j = fluid[q];
          batch.temperature[q] = ps.temperature[j], batch.volume[q] = heat_volume(P, ps, j), batch.material[q] = ps.material[j];
          one_material &= batch.material[q] == batch.material[0];
        }
        if (m > 0) fit_mass = P.materials.of(batch.material[0]).mass;
        carriers = CarrierArrays{cx, cr2, batch.temperature.data(), batch.volume.data(), batch.material.data(), fluid.data()};
      }
      [[maybe_unused]] FitLanes<Dim> fit;
      for (std::uint32_t w = b; w < e; ++w) {
        if (P.is_fluid(ps.material[w])) continue;
        const Vec<Dim> xw = load_vec<Dim>(ps.pos, w);
        candidate_distances<Dim>(xw, cx, m, cr2);
        const int count = select_inside(cr2, m, P.support2, index);
        [[maybe_unused]] ThermalFace face;
        [[maybe_unused]] ThermalCondition condition{};
        [[maybe_unused]] bool mirrors = false;
        if constexpr (Heat) mirrors = wall_temperature_needs_neighbours(P, ps, w, face, condition);
        // The fit in this pass's loop (Heat: behind a face with a condition, one material around).
        [[maybe_unused]] const bool fused = Heat && mirrors && one_material && count > 0;
        [[maybe_unused]] Vec<Dim> mirror{};
        if (fused) mirror = wall_mirror_point<Dim>(ps, w, face), fit.reset();
        WallSums<Dim> sums;
        auto sum_chunks = [&]<bool Fit>() {
          // The candidate arrays as locals of the loop (read through the closure, GCC left the
          // gathers of the passes with heat scalar: scripts/check-vectorisation).
          const float* lx[Dim];
          const float* lv[Dim];
          SPATE_UNROLL for (int k = 0; k < Dim; ++k) lx[k] = cx[k], lv[k] = cv[k];
          const float *lrho = crho, *lp = cp, *lt = batch.temperature.data();
          const std::uint32_t* lindex = index;
          for (int s0 = 0; s0 < count; s0 += kChunk) {
            const int len = std::min(kChunk, count - s0);
            const std::uint32_t* chunk = lindex + s0;
            float jx[Dim][kChunk], jv[Dim][kChunk], jrho[kChunk], jp[kChunk];
            SPATE_UNROLL for (int k = 0; k < Dim; ++k) gather(lx[k], chunk, len, jx[k]), gather(lv[k], chunk, len, jv[k]);
            gather(lrho, chunk, len, jrho);
            gather(lp, chunk, len, jp);
            [[maybe_unused]] float jt[Fit ? kChunk : 1], jm2[Fit ? kChunk : 1];
            [[maybe_unused]] float fit_terms[Fit ? FitLanes<Dim>::kFields : 1][Fit ? kChunk : 1];
            if constexpr (Fit) gather(lt, chunk, len, jt);
            // Each neighbour's terms, one per vector lane (they must stay vectorised, like the
            // fluid pair terms: scripts/check-vectorisation), then added up in the visiting order;
            // with the fit, its terms (the weight V_j W_ij from this loop's kernel value and the
            // neighbour's density: wall_temperature_over's fit_weight and heat_volume) and the
            // squared distance to the mirror point (distance_squared's rounding).
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
              if constexpr (Fit) {
                float dx[Dim];
                jm2[n] = FitLanes<Dim>::offsets(jx, n, xw, mirror, P.inv_h, dx);
                FitLanes<Dim>::terms(fit_terms, n, heat_volume(true, fit_mass, jrho[n], 0.0f) * t.w, jt[n], dx);
              }
            }
            for (int n = 0; n < len; ++n) {
              WallSums<Dim> t;
              t.w = tw[n];
              t.pw = tpw[n];
              SPATE_UNROLL for (int k = 0; k < Dim; ++k) t.rho_r_w[k] = trr[k][n], t.v_w[k] = tvw[k][n];
              add_wall_pair(sums, t);
            }
            if constexpr (Fit) fit.add(fit_terms, jt, jm2, len, s0);
          }
        };
        if constexpr (Heat) {
          if (fused) sum_chunks.template operator()<true>();
          else sum_chunks.template operator()<false>();
        } else {
          sum_chunks.template operator()<false>();
        }
        WallState<Dim> st = finish_wall(P, sums, ps.material[w], xw);
        apply_wall_shear<Dim>(P, ps, w, xw, sums, st);
        ps.pressure[w] = st.p;
        ps.density[w] = st.rho;
        SPATE_UNROLL for (int k = 0; k < Dim; ++k) ps.vel[k][w] = st.v[k];
        if constexpr (Heat) {
          if (fused) {
            const std::uint32_t near = index[fit.near];
            finish_wall_temperature<Dim>(P, ps, w, face, condition, fit.sums(), fluid[near], batch.material[near]);
          } else if (mirrors) {
            wall_temperature_from<Kernel, Dim>(P, ps, w, face, condition, carriers, index, count);
          }
        }
      }
    }
  }
}

}  // namespace

}  // namespace spate::cpu
