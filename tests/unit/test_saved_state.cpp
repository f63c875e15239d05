// What a run leaves on disk, read back (io/vtk_snapshot.cpp, io/checkpoint.cpp): compressed
// snapshots with the case constants in their field data, pieces named like the in-situ blocks,
// checkpoints with the derived fields and an XDMF sidecar, and files of earlier versions.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "case/case.hpp"
#include "case/generator.hpp"
#include "io/checkpoint.hpp"
#include "io/vtk_snapshot.hpp"

namespace spate {
namespace {

const std::filesystem::path kFixtures = std::filesystem::path(SPATE_SOURCE_DIR) / "tests" / "fixtures";

std::filesystem::path scratch(const std::string& name) {
  const auto p = std::filesystem::temp_directory_path() / ("spate-unit-" + name + "-" + std::to_string(::getpid()));
  std::filesystem::remove_all(p);
  std::filesystem::create_directories(p);
  return p;
}

std::string text_of(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// The tiny case's particles with a distinct value in every exported field.
Case saved_case(int dim) {
  return parse_case(dim == 3 ? "name: t3\ndimensions: 3\ndp: 0.005\ntime: {end: 1}\ntank: {size: [0.1, 0.03, 0.05]}\n"
                               "fluid_blocks: [{min: [0, 0, 0], max: [0.05, 0.03, 0.03]}]\n"
                             : "name: t2\ndimensions: 2\ndp: 0.005\ntime: {end: 1}\ntank: {size: [0.1, 0.05]}\n"
                               "fluid_blocks: [{min: [0, 0], max: [0.05, 0.03]}]\n",
                    "saved.yaml");
}

ParticleStore particles(int dim) {
  const Case c = saved_case(dim);
  ParticleStore p = generate_particles(c);
  for (std::size_t i = 0; i < p.size(); ++i) {
    p.pressure[i] = 100.0f + 0.5f * static_cast<float>(i);
    for (int k = 0; k < dim; ++k) p.vel[k][i] = 0.001f * static_cast<float>(i) - 0.1f * static_cast<float>(k);
  }
  p.set_owned(p.size());
  return p;
}

void expect_same_exported(ParticleStore& a, ParticleStore& b) {
  ASSERT_EQ(a.size(), b.size());
  auto fa = a.fields(), fb = b.fields();
  for (std::size_t f = 0; f < fa.size(); ++f) {
    if (!fa[f].has(kExported)) continue;
    EXPECT_EQ(std::memcmp(fa[f].bytes(), fb[f].bytes(), a.size() * fa[f].elem_size), 0) << fa[f].name;
  }
}

TEST(SavedState, SnapshotRoundTripsCompressedWithFieldData) {
  for (int dim : {2, 3}) {
    const auto dir = scratch("snapshot");
    ParticleStore all = particles(dim);
    // Two pieces, as two slabs write them.
    ParticleStore half[2] = {ParticleStore(dim), ParticleStore(dim)};
    for (std::size_t i = 0; i < all.size(); ++i) half[i % 2].append_from(all, i);
    for (int s = 0; s < 2; ++s) {
      half[s].set_owned(half[s].size());
      write_vtp_piece(dir / "step" / ("slab_" + std::to_string(s) + ".vtp"), half[s], s);
    }
    write_vtm(dir / "step.vtm", {"step/slab_0.vtp", "step/slab_1.vtp"}, {{"dp", 0.005}, {"time", 0.1 + 1e-17}, {"step", 42}});
    Snapshot back = read_snapshot(dir / "step.vtm", dim);
    ASSERT_EQ(back.pieces.size(), 2u);
    EXPECT_EQ(back.slabs, (std::vector<int>{0, 1}));
    for (int s = 0; s < 2; ++s) expect_same_exported(half[s], back.pieces[s]);
    EXPECT_EQ(back.value("dp", 0), 0.005);
    EXPECT_EQ(back.value("time", 0), 0.1 + 1e-17) << "field data keeps every bit of a double";
    EXPECT_EQ(back.value("step", 0), 42);
    const std::string vtm = text_of(dir / "step.vtm"), piece = text_of(dir / "step" / "slab_1.vtp");
    EXPECT_NE(vtm.find("name=\"slab_1\""), std::string::npos) << "blocks are named like the in-situ dataset's";
    EXPECT_NE(piece.find("compressor=\"vtkZLibDataCompressor\""), std::string::npos);
    EXPECT_NE(piece.find("type=\"Int32\" Name=\"connectivity\""), std::string::npos) << "32-bit connectivity";
    std::filesystem::remove_all(dir);
  }
}

// A snapshot written before compression (raw appended data) reads back as the checkpoint of the
// same step holds it.
TEST(SavedState, RawSnapshotOfEarlierVersionsStillReads) {
  const auto dir = kFixtures / "run_v0_tiny_2d";
  Snapshot s = read_snapshot(dir / "snapshots" / "step_00000003.vtm", 2);
  ASSERT_EQ(s.pieces.size(), 1u);
  EXPECT_TRUE(s.field_data.empty());
  ParticleStore ck;
  const CheckpointMeta meta = read_checkpoint(dir / "checkpoints" / "checkpoint_step_00000003.h5", ck);
  EXPECT_FALSE(meta.derived_saved) << "that checkpoint predates the derived datasets";
  ParticleStore& p = s.pieces[0];
  ASSERT_EQ(p.size(), ck.size());
  std::size_t fluid_with_pressure = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const std::uint32_t id = p.id[i];  // the checkpoint is ordered by id
    for (int k = 0; k < 2; ++k) {
      EXPECT_EQ(p.pos[k][i], ck.pos[k][id]);
      EXPECT_EQ(p.vel[k][i], ck.vel[k][id]);
    }
    EXPECT_EQ(p.density[i], ck.density[id]);
    EXPECT_EQ(p.material[i], ck.material[id]);
    fluid_with_pressure += p.material[i] == 0 && p.pressure[i] != 0;
  }
  EXPECT_GT(fluid_with_pressure, 0u) << "the snapshot's pressure was read";
}

TEST(SavedState, CheckpointKeepsDerivedFieldsAndHasAnXdmfSidecar) {
  const auto dir = scratch("checkpoint");
  ParticleStore p = particles(3), back;
  CheckpointMeta meta;
  meta.step = 7;
  meta.time = 0.25;
  // A checkpoint is read as input: a real time step and the case it belongs to.
  const Case c = saved_case(3);
  meta.dt = 1e-4;
  meta.case_name = c.name;
  meta.case_yaml = c.source_yaml;
  meta.geometry_hash = geometry_hash(c);
  write_checkpoint(dir / "checkpoint_step_00000007.h5", meta, p);
  const CheckpointMeta read = read_checkpoint(dir / "checkpoint_step_00000007.h5", back);
  EXPECT_TRUE(read.derived_saved);
  expect_same_exported(p, back);
  const std::string xdmf = text_of(xdmf_sidecar(dir / "checkpoint_step_00000007.h5"));
  EXPECT_EQ(xdmf_sidecar(dir / "checkpoint_step_00000007.h5").filename(), "checkpoint_step_00000007.xmf2");
  EXPECT_NE(xdmf.find("NumberOfElements=\"" + std::to_string(p.size()) + "\""), std::string::npos);
  for (const char* needle : {"GeometryType=\"X_Y_Z\"", "checkpoint_step_00000007.h5:/particles/x", "Name=\"velocity\"", "JOIN($0, $1, $2)",
                             "Name=\"pressure\"", "Name=\"kind\"", "<Time Value=\"0.25\"/>"})
    EXPECT_NE(xdmf.find(needle), std::string::npos) << needle;
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace spate
