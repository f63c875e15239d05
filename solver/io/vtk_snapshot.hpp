#pragma once
// Particle snapshots that ParaView 5.11 opens directly: one PolyData piece (.vtp, raw appended
// binary) per slab, a multiblock (.vtm) per output step with one block per slab, and a .pvd index
// that makes the steps one time series.
#include <filesystem>
#include <string>
#include <vector>

#include "../particles/particle_store.hpp"

namespace spate {

// Writes owned particles [0, owned) of one slab.
void write_vtp_piece(const std::filesystem::path& path, ParticleStore& particles, int slab);
void write_vtm(const std::filesystem::path& path, const std::vector<std::string>& piece_files);

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
