// The CPU passes with heat transfer: the fluid pass with the fused conduction sum and the wall
// state pass with the mirrored temperatures (fluid_pass.hpp's templates with Heat), and the wall
// temperature pass, in a translation unit of their own beside cpu_backend.cpp's passes without.
#include <algorithm>
#include <cmath>
#include <vector>

#include "fluid_pass.hpp"

#include "../../physics/dispatch.hpp"

namespace spate::cpu {

namespace {

template <class Kernel, int Dim>
void wall_temperature_from(const PhysicsParams& P, ParticleStore& ps, std::uint32_t w, const ThermalFace& face,
                           ThermalCondition condition, const CarrierArrays& c, const std::uint32_t* inside, int n) {
  if (n == 0) return finish_wall_temperature<Dim>(P, ps, w, face, condition, LinearFitSums<Dim>{}, 0, -1);  // a dry wall
  bool one_material = true;
  for (int s = 1; s < n; ++s) one_material &= c.material[inside[s]] == c.material[inside[0]];
  if (!one_material) {
    wall_temperature_over<Kernel, Dim>(P, ps, w, [&](auto&& fn) {
      for (int s = 0; s < n; ++s) fn(c.carrier[inside[s]]);
    });
    return;
  }
  const Vec<Dim> xw = load_vec<Dim>(ps.pos, w);
  const Vec<Dim> mirror = wall_mirror_point<Dim>(ps, w, face);
  FitLanes<Dim> fit;
  fit.reset();
  for (int s0 = 0; s0 < n; s0 += kChunk) {
    const int len = std::min(kChunk, n - s0);
    const std::uint32_t* chunk = inside + s0;
    float jx[Dim][kChunk], jr2[kChunk], jt[kChunk], jv[kChunk];
    SPATE_UNROLL for (int k = 0; k < Dim; ++k) gather(c.x[k], chunk, len, jx[k]);
    gather(c.r2, chunk, len, jr2);
    gather(c.t, chunk, len, jt);
    gather(c.volume, chunk, len, jv);
    // LinearFitSums::add's terms and the distance to the mirror point (distance_squared's
    // rounding), one neighbour per vector lane (scripts/check-vectorisation).
    typename FitLanes<Dim>::Terms terms;
    float jm2[kChunk];
    for (int s = 0; s < len; ++s) {  // must vectorise: wall-fit-terms
      float dx[Dim];
      jm2[s] = FitLanes<Dim>::offsets(jx, s, xw, mirror, P.inv_h, dx);
      FitLanes<Dim>::terms(terms, s, fit_weight<Kernel>(P, jv[s], jr2[s]), jt[s], dx);
    }
    fit.add(terms, jt, jm2, len, s0);
  }
  const std::uint32_t near = inside[fit.near];
  finish_wall_temperature<Dim>(P, ps, w, face, condition, fit.sums(), c.carrier[near], c.material[near]);
}

}  // namespace

void fluid_rates_with_heat(ParticleStore& p, const CellGrid& grid, const PhysicsParams& P, ParticleRange range) {
  dispatch_pair_loop(P, [&]<class Kernel, int Dim, bool Gamma7, bool Multiphase, bool MovingWalls, bool Riemann>() {
    fluid_rates_batched<Kernel, Dim, Gamma7, Multiphase, MovingWalls, Riemann, true>(p, grid, P, range);
  });
}

void wall_state_with_heat(ParticleStore& p, const CellGrid& grid, const PhysicsParams& P) {
  dispatch_kernel_dim(P, [&]<class Kernel, int Dim>() { wall_state_batched<Kernel, Dim, true>(p, grid, P); });
}

// Heat transfer's wall pass when a solid carries its own temperature (otherwise wall_state_batched
// mirrors the temperatures over the fluid it selects, and this pass only sets the conductivities):
// every particle's conductivity, and for the particles behind a tank face with a condition
// wall_temperature_from over the candidates that may carry a temperature (carries_temperature),
// collected once per cell with their temperatures and volumes (a dry tank cell costs a scan of its
// own particles), and of those only the ones inside the support, selected as the fluid pass selects.
template <class Kernel, int Dim>
void wall_temperature_batched(ParticleStore& ps, const CellGrid& grid, const PhysicsParams& params) {
  const PhysicsParams P = params;
  const CellGridView v = grid.view();
  const auto cells = static_cast<std::int64_t>(grid.owned_cell_count());
  const auto particles = static_cast<std::int64_t>(v.start[cells]);
#pragma omp parallel if (particles > pair_grain())
  {
    std::vector<std::uint32_t> carriers, inside;
    std::vector<float> cx[Dim], cr2, ct, cv;
    std::vector<std::uint8_t> cm;
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
        ct.resize(count + kSelectSlack), cv.resize(count + kSelectSlack), cm.resize(count + kSelectSlack);
      }
      float* px[Dim];
      SPATE_UNROLL for (int k = 0; k < Dim; ++k) {
        px[k] = cx[k].data();
        for (int q = 0; q < count; ++q) px[k][q] = ps.pos[k][carriers[q]];
      }
      for (int q = 0; q < count; ++q) {
        const std::uint32_t j = carriers[q];
        ct[q] = ps.temperature[j], cv[q] = heat_volume(P, ps, j), cm[q] = ps.material[j];
      }
      const CarrierArrays arrays{px, cr2.data(), ct.data(), cv.data(), cm.data(), carriers.data()};
      for (std::uint32_t i = b; i < e; ++i) {
        ThermalFace face;
        ThermalCondition condition;
        if (!wall_temperature_needs_neighbours(P, ps, i, face, condition)) continue;
        candidate_distances<Dim>(load_vec<Dim>(ps.pos, i), px, count, cr2.data());
        const int n = select_inside(cr2.data(), count, P.support2, inside.data());
        wall_temperature_from<Kernel, Dim>(P, ps, i, face, condition, arrays, inside.data(), n);
      }
    }
  }
}

void wall_temperature(ParticleStore& p, const CellGrid& grid, const PhysicsParams& P) {
  if (wall_state_mirrors_temperature(P)) {
    // The wall state pass has mirrored the temperatures: the other particles' conductivities.
    const auto n = static_cast<std::int64_t>(grid.view().start[grid.owned_cell_count()]);
#pragma omp parallel for schedule(static) if (n > cheap_grain())
    for (std::int64_t i = 0; i < n; ++i) {
      ThermalFace face;
      ThermalCondition condition;
      wall_temperature_needs_neighbours(P, p, static_cast<std::uint32_t>(i), face, condition);
    }
    return;
  }
  dispatch_kernel_dim(P, [&]<class Kernel, int Dim>() { wall_temperature_batched<Kernel, Dim>(p, grid, P); });
}

}  // namespace spate::cpu
