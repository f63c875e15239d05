#pragma once
// Particle snapshots that ParaView 5.11 opens directly: one PolyData piece (.vtp) per slab, a
// multiblock (.vtm) per output step with one block per slab named `slab_<k>` (the names of the
// in-situ dataset's blocks), and a .pvd index that makes the steps one time series.
//
// A piece holds every exported field of the field registry (the points, velocity, density,
// pressure, id, kind) under its exported name plus the owning slab (`device`), in appended binary,
// zlib-compressed in blocks, with 32-bit connectivity while the piece has fewer than 2^31
// particles. The .vtm's field data carries what pipelines read from the in-situ dataset (dp,
// dimensions, smoothing_length, ...) and the step's `time`, `step` and `TimeValue`, so a saved
// snapshot can be fed to the same pipelines after the run (spate post), and read_snapshot() gives
// back the particles exactly as they were written.
#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "../particles/particle_store.hpp"

namespace spate {

using FieldData = std::vector<std::pair<std::string, double>>;

// Writes owned particles [0, owned) of one slab; `fluids` > 1 adds the `phase` array.
void write_vtp_piece(const std::filesystem::path& path, ParticleStore& particles, int slab, int fluids = 1);
// Reads a piece written by write_vtp_piece (compressed or, as before spate 0.1, raw) into a store of
// dimension `dim`, every particle owned: each exported field from the array of its exported name
// (a field the file lacks stays zero). Throws std::runtime_error naming the file.
ParticleStore read_vtp_piece(const std::filesystem::path& path, int dim);
void write_vtm(const std::filesystem::path& path, const std::vector<std::string>& piece_files, const FieldData& field_data = {});

struct Snapshot {
  FieldData field_data;               // the .vtm's (empty for snapshots written before spate 0.1 had it)
  std::vector<ParticleStore> pieces;  // one per block, in block order; every particle owned
  std::vector<int> slabs;             // each piece's slab (block index)
  double value(const std::string& name, double fallback) const;
};
// Reads a .vtm written by write_vtm and its pieces into stores of dimension `dim` (fields a piece
// lacks stay zero). Throws std::runtime_error naming the file and what is wrong.
Snapshot read_snapshot(const std::filesystem::path& vtm, int dim);

// The entries (time, file relative to the .pvd) of a .pvd index, in file order; none if it is missing.
std::vector<std::pair<double, std::string>> read_pvd(const std::filesystem::path& path);

class PvdIndex {
 public:
  explicit PvdIndex(std::filesystem::path path) : path_(std::move(path)) {}
  // Adds a step and rewrites the index (atomically: readers never see half a file).
  void add(double time, const std::string& relative_file);
  // Keeps the entries up to `time` (a restart continues an existing series).
  void load_existing(double up_to_time);

 private:
  std::filesystem::path path_;
  std::vector<std::pair<double, std::string>> entries_;
};

}  // namespace spate
