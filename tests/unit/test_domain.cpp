// Domain (solver/domain/slab_topology.hpp over HostSlabArrays, as the CPU backend runs it): a halo
// refresh brings every ghost the current value of its source particle; migration sends every
// particle to the slab that owns its column, losing none.
#include <gtest/gtest.h>
#include <atomic>
#include <chrono>

#include <limits>
#include <mutex>
#include <random>
#include <set>
#include <thread>

#include "comm/in_process_transport.hpp"
#include "domain/host_slab_arrays.hpp"
#include "domain/particle_checks.hpp"
#include "domain/slab_topology.hpp"
#include "domain/slab_layout.hpp"
#include "grid/cell_grid.hpp"
#include "physics/params.hpp"
#include "sim/slab_worker.hpp"

namespace spate {
namespace {

Lattice periodic_lattice(int dim) {
  Lattice L;
  L.dim = dim;
  for (int a = 0; a < dim; ++a) {
    L.cells[a] = a == 0 ? 9 : 4;
    L.cell_size[a] = 0.03f;
    L.inv_cell[a] = 1.0f / L.cell_size[a];
    L.periodic[a] = a < dim - 1;  // every axis but the vertical one
    L.period[a] = L.periodic[a] ? L.cells[a] * L.cell_size[a] : 0.0f;
  }
  return L;
}

ParticleStore random_store(const Lattice& L, std::size_t n, unsigned seed, std::uint32_t first_id = 0) {
  std::mt19937 rng(seed);
  ParticleStore p(L.dim);
  p.resize(n);
  for (int a = 0; a < L.dim; ++a) {
    // The non-periodic vertical axis keeps its outermost cells empty, as generated cases do.
    const float lo = L.periodic[a] ? 0.0f : L.cell_size[a];
    const float hi = L.periodic[a] ? L.period[a] : L.upper(a) - L.cell_size[a];
    std::uniform_real_distribution<float> u(lo, hi);
    for (std::size_t i = 0; i < n; ++i) p.pos[a][i] = std::min(u(rng), std::nextafter(hi, lo));
  }
  for (std::size_t i = 0; i < n; ++i) {
    p.id[i] = first_id + static_cast<std::uint32_t>(i);
    p.material[i] = 0;  // fluid
    p.density[i] = 1000.0f;
  }
  p.set_owned(n);
  return p;
}

// Three slabs on three threads; `body(slab, transport)` runs on each; failures are collected.
template <class Body>
void on_three_slabs(bool periodic_x, Body body) {
  InProcessHub hub(3);
  std::vector<std::string> errors(3);
  std::vector<std::thread> threads;
  for (int s = 0; s < 3; ++s)
    threads.emplace_back([&, s] {
      try {
        auto t = hub.endpoint(s, periodic_x);
        body(s, *t);
      } catch (const std::exception& e) {
        errors[s] = e.what();
        hub.abandon();
      }
    });
  for (auto& t : threads) t.join();
  for (auto& e : errors) EXPECT_TRUE(e.empty()) << e;
}

// A position a hair below the lower end of a periodic axis comes back inside [lower, upper): adding
// the period rounds it to the upper end itself, whose cell does not exist (a particle of the
// Rayleigh-Taylor case at dp = 0.01 was reported as having left the domain at x = 1 of [0, 1]).
TEST(Wrap, EveryPeriodicPositionLandsInsideTheLattice) {
  Lattice L = periodic_lattice(2);
  L.origin[0] = 0.0f;
  for (const float x0 : {-1e-9f, -1e-8f, -std::numeric_limits<float>::denorm_min(), -0.01f, L.upper(0), L.upper(0) + 0.01f}) {
    float x = x0;
    wrap_periodic(L, x, 0);
    EXPECT_GE(x, L.origin[0]) << x0;
    EXPECT_LT(x, L.upper(0)) << x0;
    EXPECT_EQ(position_fault(L, x, 0), PositionFault::None) << x0;
    EXPECT_LT(L.cell_of(x, 0), L.cells[0]) << x0;
  }
}

// The cell decides too: a position an ulp below the upper end whose cell rounds to the cell count
// (the 1 mm Poiseuille channel at dp = L/80: 0.6 mm long, 18 cells; x = 0.00059999997 times
// 1 / cell_size = 30000 rounds to 18.0).
TEST(Wrap, APositionWhoseCellRoundsPastTheLastComesBack) {
  Lattice L = periodic_lattice(2);
  L.origin[0] = 0.0f;
  L.cells[0] = 18;
  L.cell_size[0] = 6.0e-4f / 18;
  L.inv_cell[0] = 1.0f / L.cell_size[0];
  L.period[0] = L.upper(0);
  int found = 0;
  for (float x0 = L.upper(0); found < 4 && x0 > 0.99f * L.upper(0); x0 = nextafterf(x0, 0.0f)) {
    if (x0 >= L.upper(0) || L.cell_of(x0, 0) < L.cells[0]) continue;  // only the rounding case
    ++found;
    float x = x0;
    wrap_periodic(L, x, 0);
    EXPECT_GE(x, L.origin[0]) << x0;
    EXPECT_LT(x, L.upper(0)) << x0;
    EXPECT_EQ(position_fault(L, x, 0), PositionFault::None) << x0;
  }
  EXPECT_GT(found, 0) << "no position below the upper end rounds into the cell past the last";
  float inside = 0.5f * L.upper(0), before = inside;  // and a position inside is left alone
  wrap_periodic(L, inside, 0);
  EXPECT_EQ(inside, before);
}

TEST(Halo, RefreshBringsCurrentValuesToEveryGhost) {
  for (int dim : {2, 3}) {
    const Lattice L = periodic_lattice(dim);
    const ParticleStore all = random_store(L, dim == 2 ? 400 : 900, 7u + dim);
    const SlabLayout layout = SlabLayout::uniform(L.cells[0], 3);
    on_three_slabs(true, [&](int s, SlabTransport& t) {
      ParticleStore p(dim);
      for (std::size_t i = 0; i < all.size(); ++i)
        if (layout.owner_of(L.cell_of(all.pos[0][i], 0)) == s) p.append_from(all, i);
      p.set_owned(p.size());
      CellGrid grid;
      grid.configure(L, layout.faces[s], layout.faces[s + 1]);
      HostSlabArrays arrays(p, grid);
      SlabTopology topology;
      topology.rebuild(arrays, grid, layout, t);
      EXPECT_GT(p.ghosts(), 0u);
      // New values on the owners after the halo was built (as wall pressures are each step).
      for (std::size_t i = 0; i < p.owned(); ++i) {
        p.pressure[i] = 10.0f * static_cast<float>(p.id[i]);
        p.density[i] = 1000.0f + static_cast<float>(p.id[i]);
      }
      for (std::size_t g = p.owned(); g < p.size(); ++g) p.pressure[g] = -1.0f;
      topology.begin_refresh(arrays);
      topology.finish_refresh(arrays, t);
      for (std::size_t g = p.owned(); g < p.size(); ++g) {
        EXPECT_EQ(p.pressure[g], 10.0f * static_cast<float>(p.id[g])) << "ghost of particle " << p.id[g];
        EXPECT_EQ(p.density[g], 1000.0f + static_cast<float>(p.id[g])) << "ghost of particle " << p.id[g];
      }
    });
  }
}

TEST(Migrate, EveryParticleEndsOnItsOwnerAndNoneIsLost) {
  for (bool periodic_x : {false, true}) {
    Lattice L = periodic_lattice(3);
    L.periodic[0] = periodic_x;
    if (!periodic_x) L.period[0] = 0.0f;
    const SlabLayout layout = SlabLayout::uniform(L.cells[0], 3);
    std::mutex m;
    std::multiset<std::uint32_t> ids_after;
    std::int64_t moved_seen = -1;
    on_three_slabs(periodic_x, [&](int s, SlabTransport& t) {
      // Each slab starts with particles anywhere in the domain, as after faces moved a long way.
      ParticleStore p = random_store(L, 300, 100u + s, static_cast<std::uint32_t>(1000 * s));
      CellGrid grid;
      grid.configure(L, layout.faces[s], layout.faces[s + 1]);
      HostSlabArrays arrays(p, grid);
      const std::int64_t moved = SlabTopology().rebuild(arrays, grid, layout, t);
      for (std::size_t i = 0; i < p.owned(); ++i)
        EXPECT_EQ(layout.owner_of(L.cell_of(p.pos[0][i], 0)), s) << "particle " << p.id[i] << " on slab " << s;
      std::lock_guard lock(m);
      ids_after.insert(p.id.begin(), p.id.begin() + static_cast<std::ptrdiff_t>(p.owned()));
      if (moved_seen >= 0) {
        EXPECT_EQ(moved, moved_seen);  // the same global count on every slab
      }
      moved_seen = moved;
    });
    std::multiset<std::uint32_t> expected;
    for (std::uint32_t s = 0; s < 3; ++s)
      for (std::uint32_t i = 0; i < 300; ++i) expected.insert(1000 * s + i);
    EXPECT_EQ(ids_after, expected);
    EXPECT_GT(moved_seen, 300);  // about two thirds of the 900 particles had to move
  }
}

// The checkpoint writer's collective: every slab's buffer on slab 0 only, in slab order, twice in a
// row (the hub's slots are reusable after a gather moved them out).
TEST(Transport, GatherBringsEverySlabsBufferToSlabZeroOnly) {
  std::mutex m;
  std::vector<std::vector<std::string>> seen(3);
  on_three_slabs(false, [&](int s, SlabTransport& t) {
    for (int round = 0; round < 2; ++round) {
      const std::string mine = std::to_string(round) + ":" + std::string(static_cast<std::size_t>(s + 1) * 1000, static_cast<char>('a' + s));
      const auto all = t.gather(Bytes(mine.begin(), mine.end()));
      std::lock_guard lock(m);
      for (auto& b : all) seen[s].emplace_back(b.begin(), b.end());
    }
  });
  EXPECT_TRUE(seen[1].empty());
  EXPECT_TRUE(seen[2].empty());
  ASSERT_EQ(seen[0].size(), 6u);
  for (int round = 0; round < 2; ++round)
    for (int k = 0; k < 3; ++k)
      EXPECT_EQ(seen[0][round * 3 + k], std::to_string(round) + ":" + std::string(static_cast<std::size_t>(k + 1) * 1000, static_cast<char>('a' + k)));
}

// post()/collect(): each slab gets exactly its neighbours' buffers of the same round although the
// slabs run apart (each sleeps a different, changing time before posting) and nothing else makes
// them meet between rounds (the mailboxes are reused every second round). Also after an
// exchange() in between, and with a slab that is its own neighbour (one slab, periodic x).
TEST(Transport, PostedBuffersArriveInOrderWhileSlabsRunApart) {
  auto msg = [](char side, int slab, int round) { return std::string(1, side) + std::to_string(slab) + "/" + std::to_string(round) + std::string(static_cast<std::size_t>(slab) * 5, '.'); };
  for (const bool periodic : {false, true}) {
    on_three_slabs(periodic, [&](int s, SlabTransport& t) {
      const int l = t.left_of(s), r = t.right_of(s);
      for (int round = 0; round < 8; ++round) {
        std::this_thread::sleep_for(std::chrono::milliseconds((s * 3 + round) % 4));
        const std::string to_left = msg('L', s, round), to_right = msg('R', s, round);
        t.post(Bytes(to_left.begin(), to_left.end()), Bytes(to_right.begin(), to_right.end()));
        if (round == 5) {
          Bytes a, b;
          t.exchange(Bytes{'x'}, Bytes{'y'}, a, b);
          EXPECT_EQ(a, l >= 0 ? Bytes{'y'} : Bytes{});
        }
        Bytes from_left, from_right;
        t.collect(from_left, from_right);
        EXPECT_EQ(std::string(from_left.begin(), from_left.end()), l >= 0 ? msg('R', l, round) : "") << "slab " << s << " round " << round;
        EXPECT_EQ(std::string(from_right.begin(), from_right.end()), r >= 0 ? msg('L', r, round) : "") << "slab " << s << " round " << round;
      }
    });
  }
  InProcessHub alone(1);
  auto t = alone.endpoint(0, true);
  t->post(Bytes{'l'}, Bytes{'r'});
  Bytes from_left, from_right;
  t->collect(from_left, from_right);
  EXPECT_EQ(from_left, Bytes{'r'});
  EXPECT_EQ(from_right, Bytes{'l'});
}

// A slab that fails while its neighbour waits in collect() releases it with PeerFailure.
TEST(Transport, CollectDoesNotHangWhenANeighbourFails) {
  InProcessHub hub(2);
  std::atomic<bool> released = false;
  std::thread waiter([&] {
    auto t = hub.endpoint(0, false);
    t->post(Bytes{}, Bytes{'a'});
    Bytes a, b;
    try {
      t->collect(a, b);
    } catch (const PeerFailure&) {
      released = true;
    }
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  hub.abandon();
  waiter.join();
  EXPECT_TRUE(released);
}

// The measured balancer spreads a slab's timed seconds over its columns: the wall phase over the
// walls, the fluid phase over the fluid, the sort over every particle, so the histogram sums back
// to the measured time.
TEST(MeasuredCosts, SpreadTheTimedSecondsOverTheColumns) {
  const Lattice L = periodic_lattice(2);
  ParticleStore p = random_store(L, 90, 7);
  const MaterialTable M;  // one fluid (material 0), the tank
  for (std::size_t i = 0; i < p.owned(); ++i) p.material[i] = i % 3 == 0 ? M.tank() : 0;
  const PhaseCosts c = measured_column_costs(p, L, M, 0.3, 1.2);
  std::int64_t wall = 0, fluid = 0;
  for (int k = 0; k < L.cells[0]; ++k) wall += c.wall[k], fluid += c.fluid[k];
  EXPECT_NEAR(static_cast<double>(wall), 0.3e9, L.cells[0]);  // nanoseconds, rounded per column
  EXPECT_NEAR(static_cast<double>(fluid), 1.2e9, L.cells[0]);
  // Per column: its walls times the slab's seconds per wall, its fluid times seconds per fluid.
  std::vector<int> walls(L.cells[0], 0), fluids(L.cells[0], 0);
  for (std::size_t i = 0; i < p.owned(); ++i) ++(M.is_fluid(p.material[i]) ? fluids : walls)[L.cell_of(p.pos[0][i], 0)];
  for (int k = 0; k < L.cells[0]; ++k) {
    EXPECT_NEAR(static_cast<double>(c.wall[k]), 0.3e9 * walls[k] / 30.0, 1.0) << "column " << k;
    EXPECT_NEAR(static_cast<double>(c.fluid[k]), 1.2e9 * fluids[k] / 60.0, 1.0) << "column " << k;
  }
  // The sort's seconds are shared evenly by all particles of both kinds.
  const PhaseCosts sorted = measured_column_costs(p, L, M, 0.3, 1.2, 0.9);
  for (int k = 0; k < L.cells[0]; ++k) {
    EXPECT_NEAR(static_cast<double>(sorted.wall[k]), (0.3e9 / 30.0 + 0.9e9 / 90.0) * walls[k], 1.0) << "column " << k;
    EXPECT_NEAR(static_cast<double>(sorted.fluid[k]), (1.2e9 / 60.0 + 0.9e9 / 90.0) * fluids[k], 1.0) << "column " << k;
  }
  // A slab without fluid charges all its time to its walls (its fluid loop still ran over cells).
  for (std::size_t i = 0; i < p.owned(); ++i) p.material[i] = M.tank();
  const PhaseCosts dry = measured_column_costs(p, L, M, 0.3, 0.1);
  std::int64_t dry_wall = 0, dry_fluid = 0;
  for (int k = 0; k < L.cells[0]; ++k) dry_wall += dry.wall[k], dry_fluid += dry.fluid[k];
  EXPECT_NEAR(static_cast<double>(dry_wall), 0.4e9, L.cells[0]);
  EXPECT_EQ(dry_fluid, 0);
}

}  // namespace
}  // namespace spate
