// The contract of the SlabArrays primitives (domain/slab_arrays.hpp), held against both twins: the
// host one (HostSlabArrays, always) and the device one (the CUDA backend's arrays, where a GPU is
// present; skipped otherwise, and scripts/gpu-check fails on a skip). Then, on a GPU, the device
// twin against the host twin bit for bit through the whole topology of a step.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <memory>
#include <numeric>
#include <ostream>
#include <string>
#include <thread>
#include <vector>

#include "../source_dir.hpp"
#include "backend/cuda/device_runtime.hpp"
#include "case/case.hpp"
#include "case/generator.hpp"
#include "comm/in_process_transport.hpp"
#include "domain/host_slab_arrays.hpp"
#include "domain/slab_layout.hpp"
#include "domain/slab_topology.hpp"

namespace spate {
namespace {

using MakeArrays = std::function<std::unique_ptr<SlabArrays>(int dim)>;

struct Twin {
  std::string name;
  MakeArrays make;
  bool device = false;
};

void PrintTo(const Twin& t, std::ostream* os) { *os << t.name; }  // names, not bytes, in test listings

std::unique_ptr<SlabArrays> host_twin(int dim) { return std::make_unique<HostSlabArrays>(dim); }
std::unique_ptr<SlabArrays> device_twin(int dim) { return gpu::make_device_arrays(0, dim); }

Case load(const std::string& file, const std::vector<std::string>& overrides) {
  return load_case(test::source_dir() + "/cases/" + file, overrides);
}
Case small_dam_break() { return load("dam_break_2d.yaml", {"tank.size=[0.16, 0.12]"}); }
Case periodic_x_channel() { return load("poiseuille_2d.yaml", {}); }
Case periodic_y_tank() {
  return load("hydrostatic_3d.yaml", {"tank.size=[0.3, 0.2, 0.3]", "fluid_blocks=[{min: [0, 0, 0], max: [0.3, 0.2, 0.1]}]", "tank.periodic=[y]"});
}

std::uint32_t id_bound(const ParticleStore& p) { return p.id.empty() ? 0u : *std::max_element(p.id.begin(), p.id.end()) + 1; }

// Non-zero values in every field that the Ghost set leaves out, so that a slot that keeps its old
// contents shows.
void fill_rates(ParticleStore& p) {
  for (auto& f : p.fields()) {
    if (in_set(f, FieldSet::Ghost)) continue;
    float* v = reinterpret_cast<float*>(f.bytes());
    for (std::size_t i = 0; i < p.size(); ++i) v[i] = 7.0f;
  }
}

// Particles [first, size) of `p`: their fields outside Ghost are zero, their Ghost fields those of
// source[k] in `from` (with pos[shift_axis] allowed to differ by the period).
void expect_appended(ParticleStore& p, std::size_t first, ParticleStore& from, const std::vector<std::size_t>& source) {
  ASSERT_EQ(p.size() - first, source.size());
  auto to = p.fields(), src = from.fields();
  for (std::size_t f = 0; f < to.size(); ++f) {
    for (std::size_t k = 0; k < source.size(); ++k) {
      const char* got = to[f].bytes() + (first + k) * to[f].elem_size;
      if (in_set(to[f], FieldSet::Ghost)) {
        if (to[f].name == "x" || to[f].name == "y" || to[f].name == "z") continue;  // possibly shifted
        EXPECT_EQ(std::memcmp(got, src[f].bytes() + source[k] * src[f].elem_size, to[f].elem_size), 0)
            << to[f].name << " of appended particle " << k;
      } else {
        const std::vector<char> zero(to[f].elem_size, 0);
        EXPECT_EQ(std::memcmp(got, zero.data(), to[f].elem_size), 0) << to[f].name << " of appended particle " << k << " is not zero";
      }
    }
  }
}

class SlabArraysContract : public ::testing::TestWithParam<Twin> {
 protected:
  void SetUp() override {
    if (GetParam().device && gpu::device_count() == 0) GTEST_SKIP() << "no CUDA device";
  }
  std::unique_ptr<SlabArrays> make(int dim) const { return GetParam().make(dim); }
};

}  // namespace

TEST_P(SlabArraysContract, AnIdNotBelowTheBoundIsAnErrorNeverPartOfTheKey) {
  // The device sort packs (key, id) into key << id_bits | id with id_bits for the bound: a larger
  // id would land in the key bits. Ids are checked where they enter; the host twin has the limit too.
  const ParticleStore p = generate_particles(small_dam_break());
  const std::uint32_t n = id_bound(p);
  auto a = make(2);
  a->set_id_bound(n);
  a->upload(p);
  EXPECT_EQ(a->size(), p.size());
  try {
    a->set_id_bound(n - 1);  // the particle with id n - 1 is already there
    ADD_FAILURE() << "a bound below an id held was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("particle id " + std::to_string(n - 1)), std::string::npos) << e.what();
  }
  auto b = make(2);
  b->set_id_bound(n - 1);
  EXPECT_THROW(b->upload(p), std::invalid_argument);
  EXPECT_EQ(b->size(), 0u) << "nothing taken";
}

TEST_P(SlabArraysContract, TheCellTableGoesOnlyToAGridOfTheGeometryItWasBuiltFor) {
  // The table has KeyBins::table_entries() entries for the geometry of build_table; a host grid
  // reconfigured since (a balancing pass moves faces) numbers its cells differently.
  const Case c = small_dam_break();
  const Lattice L = make_lattice(c);
  ParticleStore p = generate_particles(c);
  const int nx = L.cells[0];
  CellGrid built;
  built.configure(L, 0, nx - 1);
  auto a = make(2);
  a->set_id_bound(id_bound(p));
  a->upload(p);
  a->compute_keys(built, 0, a->size(), false);
  a->sort_by_key(0, a->size());
  a->build_table(built);
  // The same grid: the particles in (cell, id) order and the table the CPU's sort gives.
  ParticleStore host(2);
  CellGrid same;
  same.configure(L, 0, nx - 1);
  a->download(host, same);
  // The reference: (cell, id) order by std::sort, the table by counting.
  const float* pos[3] = {p.pos[0].data(), p.pos[1].data(), nullptr};
  std::vector<std::uint32_t> order(p.size()), ids, starts(same.cell_count() + 1, 0u);
  std::iota(order.begin(), order.end(), 0u);
  auto cell = [&](std::uint32_t i) { return same.local_cell_of(pos, i); };
  std::sort(order.begin(), order.end(), [&](auto i, auto j) { return std::pair{cell(i), p.id[i]} < std::pair{cell(j), p.id[j]}; });
  for (const std::uint32_t i : order) {
    ASSERT_NE(cell(i), CellGrid::kOutside);
    ids.push_back(p.id[i]);
    ++starts[cell(i) + 1];
  }
  std::partial_sum(starts.begin(), starts.end(), starts.begin());
  EXPECT_EQ(std::vector<std::uint32_t>(host.id.begin(), host.id.end()), ids);
  EXPECT_EQ(same.starts(), starts);
  // One column fewer, or the same number of cells shifted by a column: refused before anything
  // is copied.
  for (const auto& [lo, hi] : {std::pair{0, nx - 2}, std::pair{1, nx}}) {
    CellGrid other;
    other.configure(L, lo, hi);
    ParticleStore untouched(2);
    EXPECT_THROW(a->download(untouched, other), std::logic_error) << lo << "-" << hi;
    EXPECT_EQ(untouched.size(), 0u);
  }
}

TEST_P(SlabArraysContract, AppendedParticlesAreZeroOutsideTheFieldsTheyCameWith) {
  // Halo ghosts arrive with their Ghost fields only; their other fields are zero (the host twin's
  // new particles start at zero; on the device the slots may hold an earlier particle's values,
  // and the next sort gathers every field). One periodic slab is its own neighbour both ways.
  ParticleStore p = generate_particles(periodic_x_channel());
  fill_rates(p);
  auto a = make(2);
  a->set_id_bound(id_bound(p));
  a->upload(p);
  const std::size_t m = 10, kept = p.size() - m;
  a->truncate(kept);  // the last m slots keep what they held
  InProcessHub hub(1);
  auto t = hub.endpoint(0, true);
  a->stage(kLeft, FieldSet::Ghost, ParticleRange{0, m}, {});
  a->stage(kRight, FieldSet::Ghost, ParticleRange{0, 0}, {});
  const auto got = a->exchange(*t, FieldSet::Ghost);
  ASSERT_EQ(got[kLeft] + got[kRight], m);
  a->append_received(kLeft, FieldSet::Ghost);
  a->append_received(kRight, FieldSet::Ghost);
  a->set_owned(a->size());
  ParticleStore host(2);
  CellGrid unused;
  a->download(host, unused);
  std::vector<std::size_t> source(m);
  std::iota(source.begin(), source.end(), 0u);
  expect_appended(host, kept, p, source);
}

TEST_P(SlabArraysContract, PeriodicImagesAreZeroOutsideTheirGhostFields) {
  const Case c = periodic_y_tank();
  const Lattice L = make_lattice(c);
  ParticleStore p = generate_particles(c);
  fill_rates(p);
  auto a = make(3);
  a->set_id_bound(id_bound(p));
  a->upload(p);
  const std::size_t kept = p.size() - 64;
  a->truncate(kept);
  CellGrid grid;
  grid.configure(L, 0, L.cells[0]);
  a->forget_images();
  a->make_images(grid, 1);
  ASSERT_GT(a->size(), kept);
  a->set_owned(a->size());
  ParticleStore host(3);
  CellGrid unused;
  a->download(host, unused);
  // Images of the first y layer, then of the last (owned columns only: one slab owns them all).
  std::vector<std::size_t> source;
  for (const int layer : {0, L.cells[1] - 1})
    for (std::size_t i = 0; i < kept; ++i)
      if (L.cell_of(p.pos[1][i], 1) == layer) source.push_back(i);
  expect_appended(host, kept, p, source);
  for (std::size_t k = 0; k < source.size(); ++k)
    EXPECT_NEAR(std::fabs(host.pos[1][kept + k] - p.pos[1][source[k]]), L.period[1], 1e-6f * L.period[1]) << "image " << k;
}

INSTANTIATE_TEST_SUITE_P(Twins, SlabArraysContract,
                         ::testing::Values(Twin{"host", host_twin, false}, Twin{"device", device_twin, true}),
                         [](const auto& twin) { return twin.param.name; });

namespace {

// Per slab after the topology of two steps on one twin: its host mirror (download), the cell
// table, and what the domain and health reductions found.
struct SlabOutcome {
  ParticleStore particles;
  std::vector<std::uint32_t> table;
  std::uint32_t position_fault = 0, unhealthy = 0;
  std::int64_t moved = 0;
};

// take_share, rebuild (migration, sort, halo, images); then every fluid particle moved 1.37 cells
// along x (towards the middle, or across the periodic boundary, which the device wraps), uploaded,
// rebuilt (particles cross faces), refreshed; the reductions; the mirror. (Not 1.5 cells: with the
// particles on a lattice of dp and cells of 3 dp that would put them on cell faces, where a
// periodic copy x + period can round into the column beyond the ghost layer; see docs/gpu.md.)
std::vector<SlabOutcome> topology(const MakeArrays& make, const Case& c, int slabs) {
  const Lattice L = make_lattice(c);
  const PhysicsParams P = physics_params(c);
  const ParticleStore global = generate_particles(c);
  const SlabLayout layout = SlabLayout::uniform(L.cells[0], slabs);
  InProcessHub hub(slabs);
  std::vector<SlabOutcome> out(slabs);
  auto body = [&](int s) {
    auto t = hub.endpoint(s, L.periodic[0]);
    CellGrid grid;
    grid.configure(L, layout.faces[s], layout.faces[s + 1]);
    ParticleStore share(c.dim);
    for (std::size_t i = 0; i < global.size(); ++i)
      if (layout.owner_of(L.cell_of(global.pos[0][i], 0)) == s) share.append_from(global, i);
    share.set_owned(share.size());
    auto a = make(c.dim);
    a->set_id_bound(id_bound(global));
    a->upload(share);
    SlabTopology topo;
    out[s].moved = topo.rebuild(*a, grid, layout, *t);
    ParticleStore host(c.dim);
    CellGrid mirror;
    mirror.configure(L, layout.faces[s], layout.faces[s + 1]);
    a->download(host, mirror);
    host.resize(host.owned());
    const float middle = L.origin[0] + 0.5f * static_cast<float>(L.cells[0]) * L.cell_size[0];
    for (std::size_t i = 0; i < host.size(); ++i) {
      if (!P.is_fluid(host.material[i])) continue;
      const float step = 1.37f * L.cell_size[0];
      host.pos[0][i] += L.periodic[0] || host.pos[0][i] < middle ? step : -step;
    }
    a->upload(host);
    out[s].position_fault = a->wrap_and_find_position_fault(L);
    out[s].moved += topo.rebuild(*a, grid, layout, *t);
    topo.begin_refresh(*a);
    topo.finish_refresh(*a, *t);
    out[s].unhealthy = a->find_unhealthy(HealthLimits(P.materials, 0.5f, 0.9f));
    out[s].particles = ParticleStore(c.dim);
    a->download(out[s].particles, mirror);
    out[s].table = mirror.starts();
  };
  std::vector<std::thread> pool;
  for (int s = 0; s < slabs; ++s) pool.emplace_back(body, s);
  for (auto& th : pool) th.join();
  return out;
}

void expect_same_outcome(std::vector<SlabOutcome>& host, std::vector<SlabOutcome>& device) {
  ASSERT_EQ(host.size(), device.size());
  for (std::size_t s = 0; s < host.size(); ++s) {
    SCOPED_TRACE("slab " + std::to_string(s));
    EXPECT_EQ(host[s].moved, device[s].moved);
    EXPECT_EQ(host[s].position_fault, device[s].position_fault);
    EXPECT_EQ(host[s].unhealthy, device[s].unhealthy);
    EXPECT_EQ(host[s].table, device[s].table);
    ASSERT_EQ(host[s].particles.size(), device[s].particles.size());
    ASSERT_EQ(host[s].particles.owned(), device[s].particles.owned());
    auto a = host[s].particles.fields(), b = device[s].particles.fields();
    const std::size_t n = host[s].particles.size(), owned = host[s].particles.owned();
    for (std::size_t f = 0; f < a.size(); ++f) {
      const std::size_t count = in_set(a[f], FieldSet::Ghost) ? n : owned;  // ghosts come down with their Ghost fields
      EXPECT_EQ(std::memcmp(a[f].bytes(), b[f].bytes(), count * a[f].elem_size), 0) << a[f].name;
    }
  }
}

}  // namespace

std::vector<std::pair<std::string, Case>> topology_cases() {
  return {{"dam_break", small_dam_break()}, {"periodic_x", periodic_x_channel()}, {"periodic_y", periodic_y_tank()}};
}

TEST(HostTwin, TheTopologyScenarioOfTheDeviceTestIsSound) {
  // What CudaArrays.* below runs, on the host twin alone: particles cross faces, nothing leaves
  // the domain, the health reduction finds the lowest fluid id, ghosts arrive. (So that a GPU
  // session does not spend its minutes on a scenario that is broken.)
  for (const auto& [name, c] : topology_cases()) {
    SCOPED_TRACE(name);
    auto out = topology(host_twin, c, 3);
    const ParticleStore global = generate_particles(c);
    std::uint32_t lowest_fluid = SlabArrays::kNoFault, found = SlabArrays::kNoFault;
    for (std::size_t i = 0; i < global.size(); ++i)
      if (physics_params(c).is_fluid(global.material[i])) lowest_fluid = std::min(lowest_fluid, global.id[i]);
    std::int64_t moved = 0;
    std::size_t owned = 0;
    for (auto& o : out) {
      EXPECT_EQ(o.position_fault, SlabArrays::kNoFault);
      EXPECT_GT(o.particles.size(), o.particles.owned()) << "ghosts";
      found = std::min(found, o.unhealthy);
      moved += o.moved;
      owned += o.particles.owned();
    }
    EXPECT_EQ(found, lowest_fluid);
    EXPECT_GT(moved, 0);
    EXPECT_EQ(owned, global.size());
  }
}

TEST(CudaArrays, TheDeviceTwinReproducesTheHostTwinThroughAStepsTopology) {
  // No physics: positions only move by the test's own shift, so every primitive (keys, radix sort,
  // table, column read, halo copies, images, refresh, wrap, the reductions, the mirror) must give
  // what the host twin gives, bit for bit, on 1 and 3 slabs, with walls, periodic x and periodic y.
  if (gpu::device_count() == 0) GTEST_SKIP() << "no CUDA device";
  for (const auto& [name, c] : topology_cases())
    for (int slabs : {1, 3}) {
      SCOPED_TRACE(name + ", " + std::to_string(slabs) + " slabs");
      auto host = topology(host_twin, c, slabs);
      auto device = topology(device_twin, c, slabs);
      expect_same_outcome(host, device);
    }
}

}  // namespace spate
