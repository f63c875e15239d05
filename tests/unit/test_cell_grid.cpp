// Cell grid (solver/grid): the step's sort (SlabTopology over HostSlabArrays, as the CPU backend
// runs it) gives (cell, id) order, and the neighbour ranges of CellGridView find exactly the
// particles within the support that brute force finds, in 2D and 3D, with periodic images and
// across slab faces made by the halo over an InProcessHub.
#include <gtest/gtest.h>

#include <map>
#include <mutex>
#include <random>
#include <set>
#include <thread>
#include <vector>

#include "comm/in_process_transport.hpp"
#include "domain/host_slab_arrays.hpp"
#include "domain/slab_topology.hpp"
#include "domain/slab_layout.hpp"
#include "grid/cell_grid.hpp"
#include "physics/params.hpp"

namespace spate {
namespace {

constexpr float kSupport = 0.026f;

// A lattice of `cells` cells per axis of one support each (slightly more, as make_lattice does).
Lattice make_test_lattice(int dim, const std::array<int, 3>& cells, const std::array<bool, 3>& periodic) {
  Lattice L;
  L.dim = dim;
  for (int a = 0; a < 3; ++a) {
    if (a >= dim) continue;
    L.cells[a] = cells[a];
    L.cell_size[a] = kSupport * 1.001f;
    L.inv_cell[a] = 1.0f / L.cell_size[a];
    L.periodic[a] = periodic[a];
    L.period[a] = periodic[a] ? static_cast<float>(cells[a]) * L.cell_size[a] : 0.0f;
  }
  return L;
}

// Random particles filling the lattice; ids are a shuffled 0..n-1 so that the sort has work to do.
ParticleStore random_particles(const Lattice& L, std::size_t n, unsigned seed, float margin = 0.0f) {
  std::mt19937 rng(seed);
  ParticleStore p(L.dim);
  p.resize(n);
  std::vector<std::uint32_t> ids(n);
  for (std::size_t i = 0; i < n; ++i) ids[i] = static_cast<std::uint32_t>(i);
  std::shuffle(ids.begin(), ids.end(), rng);
  for (int a = 0; a < L.dim; ++a) {
    // Non-periodic axes keep one empty cell at each end, as the generator's lattice does.
    const float lo = L.periodic[a] ? 0.0f : L.cell_size[a] + margin;
    const float hi = L.periodic[a] ? L.period[a] : L.upper(a) - L.cell_size[a] - margin;
    std::uniform_real_distribution<float> u(lo, hi);
    for (std::size_t i = 0; i < n; ++i) p.pos[a][i] = std::min(u(rng), std::nextafter(hi, lo));
  }
  for (std::size_t i = 0; i < n; ++i) {
    p.id[i] = ids[i];
    p.material[i] = 0;  // fluid
    p.density[i] = 1000.0f;
  }
  p.set_owned(n);
  return p;
}

// What a step does before its loops, on `p` itself (the CPU backend's arrays are its store): the
// owned particles sorted by (cell, id), halo ghosts and periodic images appended and sorted, the
// cell table in `grid`. Returns the number of ghosts.
std::size_t rebuild(ParticleStore& p, CellGrid& grid, const SlabLayout& layout, SlabTransport& t) {
  HostSlabArrays arrays(p, grid);
  SlabTopology topology;
  topology.rebuild(arrays, grid, layout, t);
  return topology.ghosts();
}

// The same on one slab without neighbours.
void sort_one_slab(ParticleStore& p, CellGrid& grid) {
  InProcessHub hub(1);
  auto t = hub.endpoint(0, false);
  rebuild(p, grid, SlabLayout::uniform(grid.lattice().cells[0], 1), *t);
}

using NeighbourSets = std::map<std::uint32_t, std::set<std::uint32_t>>;

// For every owned particle: ids of the particles (owned or ghost) the cell grid yields within the
// support. Also checks that no neighbour is yielded twice.
void collect_neighbours(const ParticleStore& p, const CellGrid& grid, NeighbourSets& out) {
  const CellGridView& view = grid.view();
  const float s2 = kSupport * kSupport;
  for (std::uint32_t c = 0; c < grid.owned_cell_count(); ++c) {
    int g[3];
    grid.global_coords(c, g);
    for (std::uint32_t i = grid.begin(c); i < grid.end(c); ++i) {
      std::set<std::uint32_t>& mine = out[p.id[i]];
      std::size_t visits = 0;
      view.for_each_neighbour_range(g, [&](std::uint32_t b, std::uint32_t e) {
        for (std::uint32_t j = b; j < e; ++j) {
          if (j == i) continue;
          float r2 = 0.0f;
          for (int a = 0; a < p.dim(); ++a) r2 += (p.pos[a][i] - p.pos[a][j]) * (p.pos[a][i] - p.pos[a][j]);
          if (r2 < s2) {
            mine.insert(p.id[j]);
            ++visits;
          }
        }
      });
      EXPECT_EQ(visits, mine.size()) << "particle " << p.id[i] << " sees a neighbour twice";
    }
  }
}

// Brute force over all pairs, with the nearest periodic image on periodic axes (the shift is added
// in float exactly as the halo adds it, so both sides compute the same r2).
NeighbourSets brute_force(const ParticleStore& p, const Lattice& L) {
  NeighbourSets out;
  const float s2 = kSupport * kSupport;
  const std::size_t n = p.owned();
  for (std::size_t i = 0; i < n; ++i) {
    auto& mine = out[p.id[i]];
    for (std::size_t j = 0; j < n; ++j) {
      if (j == i) continue;
      float r2 = 0.0f;
      for (int a = 0; a < L.dim; ++a) {
        float best = (p.pos[a][i] - p.pos[a][j]) * (p.pos[a][i] - p.pos[a][j]);
        if (L.periodic[a]) {
          for (float shift : {L.period[a], -L.period[a]}) {
            const float xj = p.pos[a][j] + shift;
            best = std::min(best, (p.pos[a][i] - xj) * (p.pos[a][i] - xj));
          }
        }
        r2 += best;
      }
      if (r2 < s2) mine.insert(p.id[j]);
    }
  }
  return out;
}

void expect_same_sets(const NeighbourSets& found, const NeighbourSets& expected) {
  ASSERT_EQ(found.size(), expected.size());
  std::size_t pairs = 0;
  for (auto& [id, set] : expected) {
    auto it = found.find(id);
    ASSERT_NE(it, found.end()) << "particle " << id << " was never visited";
    EXPECT_EQ(it->second, set) << "neighbours of particle " << id;
    pairs += set.size();
  }
  EXPECT_GT(pairs, expected.size());  // the test is not vacuous: particles do have neighbours
}

void expect_cell_id_order(const ParticleStore& p, const CellGrid& grid, std::size_t first, std::size_t last) {
  const float* pos[3] = {p.pos[0].data(), p.pos[1].data(), p.dim() == 3 ? p.pos[2].data() : nullptr};
  for (std::size_t k = first; k < last; ++k) {
    const std::uint32_t c = grid.local_cell_of(pos, k);
    ASSERT_NE(c, CellGrid::kOutside);
    EXPECT_GE(k, grid.begin(c));
    EXPECT_LT(k, grid.end(c));
    if (k > first) {
      const std::uint32_t prev = grid.local_cell_of(pos, k - 1);
      EXPECT_TRUE(prev < c || (prev == c && p.id[k - 1] < p.id[k]))
          << "slot " << k << ": (cell " << prev << ", id " << p.id[k - 1] << ") before (cell " << c << ", id " << p.id[k] << ")";
    }
  }
}

TEST(CellGrid, SortGivesCellThenIdOrder) {
  for (int dim : {2, 3}) {
    const Lattice L = make_test_lattice(dim, {7, 6, 5}, {false, false, false});
    ParticleStore p = random_particles(L, dim == 2 ? 3000 : 4000, 11u + dim);
    CellGrid grid;
    grid.configure(L, 0, L.cells[0]);
    sort_one_slab(p, grid);
    expect_cell_id_order(p, grid, 0, p.owned());
    // Every particle is in exactly one owned cell range; ghost cells are empty.
    EXPECT_EQ(grid.begin(0), 0u);
    EXPECT_EQ(grid.end(grid.owned_cell_count() - 1), p.owned());
    EXPECT_EQ(grid.begin(grid.cell_count()), p.owned());
    // Sorting a sorted store changes nothing (the order is a function of the state).
    const auto ids = p.id;
    sort_one_slab(p, grid);
    EXPECT_EQ(p.id, ids);
  }
}

TEST(CellGrid, SortOrderIndependentOfInputOrder) {
  const Lattice L = make_test_lattice(3, {5, 5, 5}, {false, false, false});
  ParticleStore a = random_particles(L, 2000, 5u);
  // The same particles in reverse storage order.
  ParticleStore b(3);
  for (std::size_t i = a.size(); i-- > 0;) b.append_from(a, i);
  b.set_owned(b.size());
  CellGrid ga, gb;
  ga.configure(L, 0, L.cells[0]);
  gb.configure(L, 0, L.cells[0]);
  sort_one_slab(a, ga);
  sort_one_slab(b, gb);
  EXPECT_EQ(a.id, b.id);
  EXPECT_EQ(a.pos[0], b.pos[0]);
}

TEST(CellGrid, NeighbourRangesAreCompleteWithoutPeriodicity) {
  for (int dim : {2, 3}) {
    const Lattice L = make_test_lattice(dim, {8, 7, 6}, {false, false, false});
    ParticleStore p = random_particles(L, dim == 2 ? 1000 : 1200, 3u + dim);
    CellGrid grid;
    grid.configure(L, 0, L.cells[0]);
    sort_one_slab(p, grid);
    NeighbourSets found;
    collect_neighbours(p, grid, found);
    expect_same_sets(found, brute_force(p, L));
  }
}

// One slab over the whole periodic x range: the halo sends the slab's first and last columns to
// itself with the period added, and makes images along a periodic y (3D).
TEST(CellGrid, NeighbourRangesAreCompleteWithPeriodicImages) {
  for (int dim : {2, 3}) {
    const Lattice L = make_test_lattice(dim, {6, 5, 4}, {true, dim == 3, false});
    ParticleStore p = random_particles(L, dim == 2 ? 800 : 1000, 17u + dim);
    const NeighbourSets expected = brute_force(p, L);
    InProcessHub hub(1);
    auto transport = hub.endpoint(0, true);
    CellGrid grid;
    grid.configure(L, 0, L.cells[0]);
    EXPECT_GT(rebuild(p, grid, SlabLayout::uniform(L.cells[0], 1), *transport), 0u);
    expect_cell_id_order(p, grid, 0, p.owned());
    expect_cell_id_order(p, grid, p.owned(), p.size());
    NeighbourSets found;
    collect_neighbours(p, grid, found);
    expect_same_sets(found, expected);
  }
}

// Three slabs on three threads, each with its own grid and halo: the union of what the slabs find
// is the brute-force answer, periodic in x or not.
TEST(CellGrid, NeighbourRangesAreCompleteAcrossSlabs) {
  for (int dim : {2, 3}) {
    for (bool periodic_x : {false, true}) {
      const Lattice L = make_test_lattice(dim, {10, 5, 4}, {periodic_x, false, false});
      const ParticleStore all = random_particles(L, dim == 2 ? 800 : 1000, 23u + dim + periodic_x);
      const NeighbourSets expected = brute_force(all, L);
      const SlabLayout layout = SlabLayout::uniform(L.cells[0], 3);
      InProcessHub hub(3);
      NeighbourSets found;
      std::mutex found_mutex;
      std::vector<std::string> errors(3);
      auto slab_body = [&](int s) {
        try {
          ParticleStore p(dim);
          for (std::size_t i = 0; i < all.size(); ++i)
            if (layout.owner_of(L.cell_of(all.pos[0][i], 0)) == s) p.append_from(all, i);
          p.set_owned(p.size());
          auto transport = hub.endpoint(s, periodic_x);
          CellGrid grid;
          grid.configure(L, layout.faces[s], layout.faces[s + 1]);
          rebuild(p, grid, layout, *transport);
          NeighbourSets mine;
          collect_neighbours(p, grid, mine);
          std::lock_guard lock(found_mutex);
          found.merge(mine);
        } catch (const std::exception& e) {
          errors[s] = e.what();
          hub.abandon();
        }
      };
      std::vector<std::thread> threads;
      for (int s = 0; s < 3; ++s) threads.emplace_back(slab_body, s);
      for (auto& t : threads) t.join();
      for (auto& e : errors) EXPECT_TRUE(e.empty()) << e;
      expect_same_sets(found, expected);
    }
  }
}

}  // namespace
}  // namespace spate
