// The field registry (particles/field_registry.hpp): one entry is all a field needs to be stored,
// sorted, migrated, copied to ghosts, checkpointed, written to snapshots and handed to in-situ
// consumers. A test-only field, registered as one FieldSpec, is followed through every layer.
#include <gtest/gtest.h>

#include "../source_dir.hpp"

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <sstream>
#include <thread>

#include "case/case.hpp"
#include "case/generator.hpp"
#include "comm/in_process_transport.hpp"
#include "io/checkpoint.hpp"
#include "io/vtk_snapshot.hpp"
#include "sim/insitu.hpp"
#include "sim/simulation.hpp"
#include "sim/slab_worker.hpp"

namespace spate {
namespace {

constexpr FieldSpec kTracer{"tracer", FieldType::F32, FieldShape::Scalar, FieldRole::State,
                            kMigrated | kCheckpointed | kGhost | kExported, "tracer", {"tracer"}};

// A value per particle that no other field has.
float tracer_of(std::uint32_t id) { return 0.25f + static_cast<float>(id) * 1.5f; }

float* tracer(ParticleStore& p) {
  for (const FieldRef& f : p.fields())
    if (f.spec->member == "tracer") return reinterpret_cast<float*>(f.bytes());
  return nullptr;
}

}  // namespace

TEST(FieldRegistry, TheNeighbourRecordAndTheMemoryFigureFollowTheRegistry) {
  EXPECT_EQ(neighbour_record_offset(kField_pos), 0);
  EXPECT_EQ(neighbour_record_offset(kField_vel), 3);
  EXPECT_EQ(neighbour_record_offset(kField_density), 6);
  EXPECT_EQ(neighbour_record_offset(kField_pressure), 7);
  EXPECT_EQ(neighbour_record_offset(kField_id), -1);
  // 3D: position, velocity, acceleration, previous acceleration (48), density, pressure and their
  // rates (16), id (4), material (1); plus the sort's key, permutation and scratch word (12).
  EXPECT_EQ(builtin_field_bytes(3), 69u);
  EXPECT_EQ(ParticleStore(3).bytes_per_particle(), 81u);
  EXPECT_EQ(ParticleStore(2).bytes_per_particle(), 81u - 4 * 4);
  // One checkpoint dataset per component of every checkpointed field; version 1 named the material "kind".
  std::vector<std::string> names;
  for (auto& d : checkpoint_datasets(2)) names.push_back(d.name);
  EXPECT_EQ(names, (std::vector<std::string>{"x", "y", "vx", "vy", "density", "id", "material", "ax", "ay", "density_rate"}));
  EXPECT_EQ(checkpoint_datasets(2, 1)[6].name, "kind");
}

// An optional field (kOptional: surface tension's colour gradient, shifting's displacement) is in the stores made while a
// run that needs it holds OptionalFields(true), and costs every other run nothing: not in fields(),
// not in the ghost or refresh sets, not in the bytes per particle.
TEST(FieldRegistry, AnOptionalFieldIsOnlyInTheStoresOfRunsThatNeedIt) {
  auto has_colour = [](ParticleStore& p) {
    for (auto& f : p.fields())
      if (f.spec == &kParticleFields[kField_colour_gradient]) return true;
    return false;
  };
  ParticleStore plain(2);
  EXPECT_FALSE(has_colour(plain));
  {
    const OptionalFields off(false);
    ParticleStore p(2);
    EXPECT_FALSE(has_colour(p));
  }
  {
    const OptionalFields on(true);
    ParticleStore p(2);
    EXPECT_TRUE(has_colour(p));
    // The colour gradient, the shifting displacement and the density gradient, two floats each in 2D.
    EXPECT_EQ(p.bytes_per_particle(), plain.bytes_per_particle() + 6 * sizeof(float));
    p.resize(5);
    EXPECT_EQ(p.colour_gradient[1].size(), 5u);
  }
  ParticleStore after(2);
  EXPECT_FALSE(has_colour(after));
  after.resize(5);
  EXPECT_TRUE(after.colour_gradient[0].empty());
}

// A slab takes its share of a set made under other optional fields (relaxation's worker carries
// `shift`; the generated set of a run without optional fields does not): each field comes from
// the field of the same name, never from the one at the same position. (Copied by position, a
// heat run's temperatures landed in the colour gradient, and Buchner's case with `relax:` crashed.)
TEST(FieldRegistry, ASlabTakesItsShareFieldByFieldWhateverFieldsTheSetCarries) {
  const Case c = load_case(test::source_dir() + "/cases/conduction_2d.yaml");
  const OptionalFields run(FieldGroups{kThermal});  // the run's fields: thermal, not kOptional
  ParticleStore initial = generate_particles(c);
  ASSERT_EQ(initial.temperature.size(), initial.size());
  ASSERT_TRUE(initial.shift[0].empty());
  for (std::size_t i = 0; i < initial.size(); ++i) initial.temperature[i] = 280.0f + 0.01f * static_cast<float>(initial.id[i]);
  const OptionalFields worker_fields(FieldGroups{static_cast<std::uint16_t>(kThermal | kOptional)});
  const Lattice L = make_lattice(c);
  InProcessHub hub(1);
  auto t = hub.endpoint(0, c.periodic[0]);
  SlabWorker w(L, physics_params(c), *t);
  w.take_share(initial, SlabLayout::uniform(L.cells[0], 1));
  ParticleStore& p = w.particles();
  ASSERT_EQ(p.owned(), initial.size());
  ASSERT_EQ(p.shift[0].size(), p.size());
  for (std::size_t i = 0; i < p.owned(); ++i) {
    ASSERT_EQ(p.temperature[i], 280.0f + 0.01f * static_cast<float>(p.id[i])) << "particle " << p.id[i];
    ASSERT_EQ(p.shift[0][i], 0.0f);
    ASSERT_EQ(p.colour_gradient[1][i], 0.0f);
  }
}

// Two slabs run the dam break with a registered test-only field: after steps in which particles
// cross the face, every ghost, every migrated particle, the checkpoint, the snapshot piece and the
// in-situ view carry each particle's own value.
TEST(FieldRegistry, AnEntryAloneCarriesATestFieldThroughHaloMigrationCheckpointSnapshotAndInSitu) {
  const FieldExtension registered(kTracer);
  const Case c = load_case(test::source_dir() + "/cases/dam_break_2d.yaml", {"tank.size=[0.16, 0.12]"});
  const Lattice L = make_lattice(c);
  const PhysicsParams P = physics_params(c);
  ParticleStore initial = generate_particles(c);
  ASSERT_NE(tracer(initial), nullptr) << "the store did not allocate the registered field";
  for (std::size_t i = 0; i < initial.size(); ++i) tracer(initial)[i] = tracer_of(initial.id[i]);

  constexpr int kSlabs = 2;
  InProcessHub hub(kSlabs);
  std::vector<ParticleStore> finals(kSlabs);
  std::vector<std::int64_t> crossings(kSlabs);
  const auto dir = std::filesystem::path(testing::TempDir()) / "spate_field_registry";
  std::filesystem::remove_all(dir);
  auto body = [&](int s) {
    auto t = hub.endpoint(s, false);
    SlabWorker w(L, P, *t);
    // Faces in the middle of the water column: fluid crosses them from the first steps on.
    SlabLayout layout = SlabLayout::uniform(L.cells[0], kSlabs);
    layout.faces[1] = L.cell_of(0.03f, 0);
    w.take_share(initial, layout);
    w.prepare(true);
    for (int k = 0; k < 300; ++k) {
      const float dt = static_cast<float>(t->min(w.local_time_step(TimeStepControl{})));
      ASSERT_FALSE(w.step(dt).has_value());
    }
    crossings[s] = w.crossings();
    ParticleStore& p = w.particles();
    const float* v = tracer(p);
    ASSERT_NE(v, nullptr);
    ASSERT_GT(p.ghosts(), 0u);
    for (std::size_t i = 0; i < p.size(); ++i)
      ASSERT_EQ(v[i], tracer_of(p.id[i])) << (i < p.owned() ? "owned" : "ghost") << " particle " << p.id[i] << " on slab " << s;
    // Snapshot: the piece has the field under its exported name, in owned order.
    const auto piece = dir / ("slab_" + std::to_string(s) + ".vtp");
    write_vtp_piece(piece, p, s);
    ParticleStore written = read_vtp_piece(piece, p.dim());
    ASSERT_EQ(written.size(), p.owned());
    const float* w_tracer = tracer(written);
    ASSERT_NE(w_tracer, nullptr);
    for (std::size_t i = 0; i < p.owned(); ++i) EXPECT_EQ(w_tracer[i], tracer_of(p.id[i]));
    // In situ: the view has the field, pointing at the solver's own array.
    const SlabView view = slab_view(p, s, kSlabs);
    const SlabArray* a = view.array("tracer");
    ASSERT_NE(a, nullptr);
    EXPECT_EQ(a->values<float>(), v);
    EXPECT_EQ(a->type, FieldType::F32);
    finals[s] = p;
    finals[s].resize(finals[s].owned());
  };
  std::vector<std::thread> pool;
  for (int s = 0; s < kSlabs; ++s) pool.emplace_back(body, s);
  for (auto& th : pool) th.join();
  EXPECT_GT(crossings[0], 0) << "no particle migrated: the test would not see migration";

  // Checkpoint: written from the gathered particles (ordered by id) and read back.
  ParticleStore all(c.dim);
  for (auto& f : finals)
    for (std::size_t i = 0; i < f.size(); ++i) all.append_from(f, i);
  std::vector<std::uint32_t> order(all.size());
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&](auto x, auto y) { return all.id[x] < all.id[y]; });
  all.permute(0, order);
  all.set_owned(all.size());
  const auto file = dir / "checkpoint.h5";
  // A checkpoint is read as input: it needs a real header (a time step, the case it belongs to).
  CheckpointMeta meta;
  meta.dt = 1e-4;
  meta.case_name = c.name;
  meta.case_yaml = c.source_yaml;
  meta.geometry_hash = geometry_hash(c);
  write_checkpoint(file, meta, all);
  bool listed = false;
  for (auto& d : checkpoint_datasets(c.dim)) listed = listed || d.name == "tracer";
  EXPECT_TRUE(listed);
  ParticleStore back;
  read_checkpoint(file, back);
  ASSERT_EQ(back.size(), initial.size());
  for (std::size_t i = 0; i < back.size(); ++i) ASSERT_EQ(tracer(back)[i], tracer_of(back.id[i]));
}

// Without the registration the same run has no such field anywhere (the registry is the only
// place that knows it).
TEST(FieldRegistry, AnUnregisteredFieldIsNowhere) {
  ParticleStore p(2);
  EXPECT_EQ(tracer(p), nullptr);
  for (auto& d : checkpoint_datasets(2)) EXPECT_NE(d.name, "tracer");
  EXPECT_EQ(slab_view(p, 0, 1).array("tracer"), nullptr);
}

}  // namespace spate
