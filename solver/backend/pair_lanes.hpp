#pragma once
// The lane order of a fluid particle's neighbour sums, one source for every team of lanes that
// runs it: in-support neighbour n of particle i (counted in CellGridView's visiting order, i
// itself included) is added to partial sum n mod kPairLanes, each partial sum in increasing n, and
// the partial sums are added in lane order. The CPU's vectorised fluid pass (cpu/fluid_pass.hpp,
// kLanes) sums in this order; the GPU's half-warp pass (cuda_kernels.cu, HalfWarp) runs the body
// below with one lane per thread; HostLanes runs it with the lanes one after the other, which is
// how the CPU tests prove, without a GPU, that the GPU's schedule gives the CPU's bits
// (PairLanes.*). Issue 34: the per-thread loop kept about one lane in five busy at h = 2 dp
// (each thread branching on its own candidate's distance); here the half-warp tests 16 candidates
// at once and every lane takes an in-support one.
#include <cstdint>

#include "particle_updates.hpp"

namespace spate {

constexpr int kPairLanes = 16;

SPATE_HD unsigned lane_popcount(unsigned m) {
#if defined(__CUDA_ARCH__)
  return static_cast<unsigned>(__popc(m));
#else
  return static_cast<unsigned>(__builtin_popcount(m));
#endif
}

// The rank among a group's in-support candidates of the one lane `lane` takes, when `dealt`
// neighbours came before the group: neighbour n goes to lane n mod kPairLanes, so lane l takes
// number dealt + ((l - dealt) mod kPairLanes), if the group has that many.
SPATE_HD unsigned lane_rank(unsigned dealt, int lane) { return (static_cast<unsigned>(lane) - dealt) % kPairLanes; }

// Which candidate of a group of at most kPairLanes consecutive candidates lane `lane` takes: the
// group's in-support candidates are the set bits of `inside` (bit q: candidate q), numbered from
// `dealt` on in increasing q; lane l takes the one numbered n with n mod kPairLanes = l. A group
// has at most kPairLanes of them, so a lane takes at most one. -1 when it takes none.
SPATE_HD int lane_candidate(unsigned inside, unsigned dealt, int lane) {
  const unsigned rank = lane_rank(dealt, lane);
  if (rank >= lane_popcount(inside)) return -1;
  for (unsigned r = 0; r < rank; ++r) inside &= inside - 1;  // drop the `rank` lowest set bits
#if defined(__CUDA_ARCH__)
  return __ffs(static_cast<int>(inside)) - 1;
#else
  return __builtin_ctz(inside);
#endif
}

// Partial sums of N floats (the SPS passes' components); FluidRates serves the fluid pass.
template <int N>
struct LaneFloats {
  float v[N] = {};
};
template <int N>
SPATE_HD void add_lane_sums(LaneFloats<N>& total, const LaneFloats<N>& x) {
  SPATE_UNROLL for (int m = 0; m < N; ++m) total.v[m] += x.v[m];
}
template <int Dim>
SPATE_HD void add_lane_sums(FluidRates<Dim>& total, const FluidRates<Dim>& x) {
  add_pair_rates(total, x);
}

// The lanes run one after the other on the host: a "ballot" asks every lane, each lane's body runs
// in lane order on its own slot of the per-lane arrays, and the partial sums are added in lane
// order. The GPU's team (HalfWarp, cuda_kernels.cu) has the same members with one lane per thread
// (one slot).
struct HostLanes {
  static constexpr int kHeld = kPairLanes;  // the per-lane slots this team member holds
  SPATE_HD bool leader() const { return true; }
  template <class Predicate>
  SPATE_HD unsigned ballot(Predicate&& inside) const {
    unsigned m = 0;
    for (int l = 0; l < kPairLanes; ++l) m |= (inside(l) ? 1u : 0u) << l;
    return m;
  }
  template <class Body>
  SPATE_HD void for_each_lane(Body&& body) const {
    for (int l = 0; l < kPairLanes; ++l) body(l, l);
  }
  template <class Sums>
  SPATE_HD Sums sum_in_lane_order(const Sums* held) const {
    Sums total;
    for (int l = 0; l < kPairLanes; ++l) add_lane_sums(total, held[l]);
    return total;
  }
};

// The sums of particle i (at xi, in cell g) over its neighbours, in the lane order above, on a team
// of kPairLanes lanes: add(j, n, sums) adds neighbour j (its number n) to a lane's partial sums.
// The neighbours are the particles inside the support that `takes` accepts (every one, for the
// fluid and SPS passes; the wall temperatures take only the carriers of a temperature). The
// candidates are tested kPairLanes at a time (one per lane) and the in-support ones dealt to the
// lanes in order; a lane holds its dealt neighbour until every lane holds one (a batch: neighbours
// 16 b to 16 b + 15), and then all lanes run their terms together, so the terms run on full lanes
// however few candidates are inside (about 1 in 6 in 3D; 1 in 3 at h = 2 dp) but for the last
// batch. Each lane still adds its neighbours in increasing number, so the sums are the CPU's.
// The total is the team leader's (the other members' is partial).
template <int Dim, class Sums, class Team, class Fields, class Takes, class Add>
SPATE_HD Sums sum_taken_in_lanes(const PhysicsParams& P, const CellGridView& v, const Fields& f, const Vec<Dim>& xi, const int g[3],
                                 const Team& team, Takes&& takes, Add&& add) {
  constexpr std::uint32_t kNone = 0xffffffffu;
  Sums held[Team::kHeld];
  std::uint32_t pending[Team::kHeld];  // per lane: the neighbour dealt to it and not yet added
  unsigned number[Team::kHeld];        // and its number
  team.for_each_lane([&](int, int slot) { pending[slot] = kNone, number[slot] = 0; });
  const auto add_pending = [&]() {
    team.for_each_lane([&](int, int slot) {
      if (pending[slot] == kNone) return;
      add(pending[slot], number[slot], held[slot]);
      pending[slot] = kNone;
    });
  };
  unsigned dealt = 0;  // in-support neighbours before the current group
  v.for_each_neighbour_range(g, [&](std::uint32_t jb, std::uint32_t je) {
    for (std::uint32_t c0 = jb; c0 < je; c0 += kPairLanes) {
      const unsigned inside = team.ballot([&](int lane) {
        const std::uint32_t j = c0 + static_cast<std::uint32_t>(lane);
        return j < je && takes(j) && distance_squared<Dim>(xi, f.pos, j) < P.support2;
      });
      const unsigned count = lane_popcount(inside);
      const unsigned open = kPairLanes - dealt % kPairLanes;  // numbers left in the open batch
      // The group's neighbours that complete the open batch, then (when it is full) the batch's
      // terms, then the neighbours that open the next one.
      const auto deal = [&](bool completing) {
        team.for_each_lane([&](int lane, int slot) {
          const int q = lane_candidate(inside, dealt, lane);
          if (q >= 0 && (lane_rank(dealt, lane) < open) == completing) {
            pending[slot] = c0 + static_cast<std::uint32_t>(q);
            number[slot] = dealt + lane_rank(dealt, lane);
          }
        });
      };
      deal(true);
      if (count >= open) {
        add_pending();
        deal(false);
      }
      dealt += count;
    }
  });
  add_pending();
  return team.sum_in_lane_order(held);
}
// The same over every particle inside the support, add(j, sums).
template <int Dim, class Sums, class Team, class Fields, class Add>
SPATE_HD Sums sum_neighbours_in_lanes(const PhysicsParams& P, const CellGridView& v, const Fields& f, const Vec<Dim>& xi, const int g[3],
                                      const Team& team, Add&& add) {
  return sum_taken_in_lanes<Dim, Sums>(
      P, v, f, xi, g, team, [](std::uint32_t) { return true; }, [&](std::uint32_t j, unsigned, Sums& sums) { add(j, sums); });
}

// The fluid pass's sums and, with heat transfer's fused conduction (fused_heat), the conduction
// sum beside them (the CPU's fluid pass sums it in the same lanes).
template <int Dim>
struct FluidHeatRates {
  FluidRates<Dim> rates;
  float conduction = 0.0f;
};
template <int Dim>
SPATE_HD void add_lane_sums(FluidHeatRates<Dim>& total, const FluidHeatRates<Dim>& x) {
  add_pair_rates(total.rates, x.rates);
  total.conduction += x.conduction;
}

// update_fluid_rates (particle_updates.hpp) with its sums in the lane order above (the CPU's fluid
// pass, cpu/fluid_pass.hpp). Only the team's leader stores the result.
template <class Kernel, int Dim, bool Gamma7, bool Multiphase, bool MovingWalls, bool Riemann, class Team, class Fields>
SPATE_HD void update_fluid_rates_in_lanes(const PhysicsParams& P, const CellGridView& v, Fields& f, std::uint32_t i, const int g[3],
                                          const Team& team) {
  if (!P.is_fluid(f.material[i])) {
    if (team.leader()) zero_fluid_rates<Dim>(f, i);
    return;
  }
  const ParticleState<Dim> si = load_state<Dim>(f, i);
  const FluidMaterial& M = P.materials.of(si.material);
  const float mu_i = Multiphase ? particle_viscosity(P, f, i) : M.viscosity;
  // Heat transfer: the conduction sum over the same neighbours (heat_pair_term: the terms the CPU's
  // fused loop adds, from the same radial factors), then the rate and buoyancy as the CPU's.
  const bool heat = fused_heat(P);
  const ThermalMaterial& Mi = P.heat.material(si.material);
  const float ti = heat ? f.temperature[i] : 0.0f;
  const auto sums = sum_neighbours_in_lanes<Dim, FluidHeatRates<Dim>>(P, v, f, si.x, g, team, [&](std::uint32_t j, FluidHeatRates<Dim>& s) {
    add_fluid_neighbour<Kernel, Dim, Gamma7, Multiphase, MovingWalls, Riemann>(P, M, si, mu_i, f, j, s.rates);
    if (heat) s.conduction += heat_pair_term<Kernel, Dim>(P, f, Mi, si.x, ti, j);
  });
  if (!team.leader()) return;
  FluidRates<Dim> rates = sums.rates;
  store_fluid_rates<Dim>(P, M, si, f, i, rates);
  if (heat) finish_heat_rates<Dim>(P, f, i, sums.conduction);
}

// Heat transfer's wall pass (update_wall_temperature) in the lane order of the CPU's (FitLanes,
// cpu/fluid_pass.hpp): behind a tank face with a condition, the carriers of a temperature inside
// w's support (carries_temperature), carrier n into lane n mod kPairLanes of the linear fit's sums
// (LinearFitSums::add's products, the lanes merged in order); the carrier nearest the mirror point
// the first in the visiting order among equals (each lane keeps its first nearest and its number,
// the merge the nearer or, at equal distance, the earlier). Carriers of more than one material:
// the sequential fits of wall_temperature_over, as the CPU runs them then.
template <int Dim>
struct LaneFit {
  LinearFitSums<Dim> fit;
  float nearest = INFINITY;      // squared distance of the carrier nearest the mirror point
  unsigned number = 0xffffffffu;  // its number among the carriers
  std::uint32_t carrier = 0;
  int material = -1;  // the carriers' material (-1: none yet)
  int mixed = 0;      // 1: carriers of more than one material
};
template <int Dim>
SPATE_HD void add_lane_sums(LaneFit<Dim>& total, const LaneFit<Dim>& x) {
  total.fit.merge(x.fit);
  if (x.nearest < total.nearest || (x.nearest == total.nearest && x.number < total.number))
    total.nearest = x.nearest, total.number = x.number, total.carrier = x.carrier;
  if (total.material < 0) total.material = x.material;
  total.mixed |= x.mixed | (x.material >= 0 && x.material != total.material ? 1 : 0);
}
template <class Kernel, int Dim, class Team, class Fields>
SPATE_HD void update_wall_temperature_in_lanes(const PhysicsParams& P, const CellGridView& v, Fields& f, std::uint32_t w, const int g[3],
                                               const Team& team) {
  if (!mirrors_temperature(P, f, w)) {  // only its conductivity: no neighbours
    if (team.leader()) update_wall_temperature<Kernel, Dim>(P, v, f, w, g);
    return;
  }
  ThermalFace face;
  ThermalCondition c;
  wall_temperature_needs_neighbours(P, f, w, face, c);
  const Vec<Dim> xw = load_vec<Dim>(f.pos, w);
  const Vec<Dim> mirror = wall_mirror_point<Dim>(f, w, face);
  const LaneFit<Dim> s = sum_taken_in_lanes<Dim, LaneFit<Dim>>(
      P, v, f, xw, g, team, [&](std::uint32_t j) { return carries_temperature(P, f, j); },
      [&](std::uint32_t j, unsigned n, LaneFit<Dim>& l) {
        const Vec<Dim> dx = load_vec<Dim>(f.pos, j) - xw;
        l.fit.add(fit_weight<Kernel>(P, heat_volume(P, f, j), dot(dx, dx)), P.inv_h * dx, f.temperature[j]);
        const float m2 = distance_squared<Dim>(mirror, f.pos, j);
        if (m2 < l.nearest) l.nearest = m2, l.number = n, l.carrier = j;
        const int m = f.material[j];
        if (l.material < 0) l.material = m;
        else if (m != l.material) l.mixed = 1;
      });
  if (!team.leader()) return;
  if (s.mixed) return update_wall_temperature<Kernel, Dim>(P, v, f, w, g);
  finish_wall_temperature<Dim>(P, f, w, face, c, s.fit, s.carrier, s.material);
}

// SPS turbulence, pass 1 (update_sps_stress) in the lane order: the velocity gradient over the
// in-support neighbours, as the CPU's batched pass (cpu/sps_passes.cpp) sums it.
template <class Kernel, int Dim, class Team, class Fields>
SPATE_HD void update_sps_stress_in_lanes(const PhysicsParams& P, const CellGridView& v, Fields& f, std::uint32_t i, const int g[3],
                                         const Team& team) {
  if (!P.is_fluid(f.material[i])) {
    if (team.leader()) store_sps_stress<Dim>(f, i, SpsStress<Dim>{}, 0.0f);
    return;
  }
  const Vec<Dim> xi = load_vec<Dim>(f.pos, i), vi = load_vec<Dim>(f.vel, i);
  const float mass_i = P.materials.of(f.material[i]).mass;
  const auto sums = sum_neighbours_in_lanes<Dim, LaneFloats<Dim * Dim>>(P, v, f, xi, g, team, [&](std::uint32_t j, LaneFloats<Dim * Dim>& s) {
    float term[Dim][Dim];
    velocity_gradient_term<Kernel, Dim>(P, xi, vi, load_vec<Dim>(f.pos, j), load_vec<Dim>(f.vel, j),
                                        sps_neighbour_mass(P, f.material[j], mass_i) / f.density[j], term);
    SPATE_UNROLL for (int a = 0; a < Dim; ++a) {
      SPATE_UNROLL for (int b = 0; b < Dim; ++b) s.v[a * Dim + b] += term[a][b];
    }
  });
  if (!team.leader()) return;
  VelocityGradient<Dim> grad;
  SPATE_UNROLL for (int a = 0; a < Dim; ++a) {
    SPATE_UNROLL for (int b = 0; b < Dim; ++b) grad.g[a][b] = sums.v[a * Dim + b];
  }
  float nu_t = 0.0f;
  const SpsStress<Dim> T = sps_stress<Dim>(P, grad, f.density[i], nu_t);
  store_sps_stress<Dim>(f, i, T, nu_t);
}

// SPS turbulence, pass 2 (add_sps_acceleration) in the lane order: the stress's divergence, a wall
// neighbour carrying i's own stress, as the CPU's batched pass sums it.
template <class Kernel, int Dim, class Team, class Fields>
SPATE_HD void add_sps_acceleration_in_lanes(const PhysicsParams& P, const CellGridView& v, Fields& f, std::uint32_t i, const int g[3],
                                            const Team& team) {
  if (!P.is_fluid(f.material[i])) return;
  const Vec<Dim> xi = load_vec<Dim>(f.pos, i);
  const SpsStress<Dim> Ti = load_sps_stress<Dim>(f, i);
  const float mass_i = P.materials.of(f.material[i]).mass;
  const auto acc = sum_neighbours_in_lanes<Dim, LaneFloats<Dim>>(P, v, f, xi, g, team, [&](std::uint32_t j, LaneFloats<Dim>& s) {
    const std::uint8_t m = f.material[j];
    const SpsStress<Dim> Tj = P.is_fluid(m) ? load_sps_stress<Dim>(f, j) : Ti;
    const Vec<Dim> a = sps_pair_term<Kernel, Dim>(P, xi, Ti, load_vec<Dim>(f.pos, j), Tj, sps_neighbour_mass(P, m, mass_i));
    SPATE_UNROLL for (int k = 0; k < Dim; ++k) s.v[k] += a[k];
  });
  if (team.leader()) SPATE_UNROLL for (int k = 0; k < Dim; ++k) f.acc[k][i] += acc.v[k];
}

}  // namespace spate
