#pragma once
// HDF5 checkpoints: the global particle state ordered by id (independent of how the run was split)
// plus the step, time, next time step and the case text, so a restart continues bit-identically
// with any number of devices or ranks. Writes go to a temporary file that is renamed into place:
// a run killed mid-write leaves the previous checkpoint intact.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>

#include "../particles/particle_store.hpp"

namespace spate {

struct CheckpointMeta {
  std::int64_t step = 0;
  double time = 0.0;
  double dt = 0.0;          // the time step the next step will take
  std::string case_name;
  std::string case_yaml;    // the effective case (after --set)
  std::string steering_log; // accepted steering changes so far (may be empty)
};

// `particles` must hold every particle, ordered by id.
void write_checkpoint(const std::filesystem::path& path, const CheckpointMeta& meta, ParticleStore& particles);
// The same file written one field at a time, so the particles never have to sit in one store:
// fill(k, out) writes field k of ParticleStore(dim).fields() (asked only for checkpoint fields) of
// all `count` particles, ordered by id, into out (count * elem_size bytes).
using CheckpointFieldFill = std::function<void(std::size_t field, char* out)>;
void write_checkpoint(const std::filesystem::path& path, const CheckpointMeta& meta, int dim, std::size_t count,
                      const CheckpointFieldFill& fill);
// Throws std::runtime_error naming the file and what is wrong.
CheckpointMeta read_checkpoint(const std::filesystem::path& path, ParticleStore& particles);

}  // namespace spate
