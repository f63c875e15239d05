#pragma once
// HDF5 checkpoints: the global particle state ordered by id (independent of how the run was split)
// plus the step, time, next time step and the case text, so a restart continues bit-identically
// with any number of devices or ranks. Writes go to a temporary file that is renamed into place:
// a run killed mid-write leaves the previous checkpoint intact.
//
// Beside the restart state a checkpoint holds the exported fields a restart recomputes (pressure),
// as they were at that step, so that it shows exactly what a snapshot of the step would
// (spate post evaluates probes on it), and an XDMF sidecar (<name>.xmf2, next to <name>.h5) that
// ParaView's XDMF reader opens: the particles as vertices with every exported field.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "../particles/particle_store.hpp"

namespace spate {

// Version 2: the material index dataset is "material" (version 1, before the field registry,
// called it "kind"; version 1 files are still read). The datasets themselves follow the field
// registry (every kCheckpointed field, one dataset per component).
constexpr int kCheckpointFormatVersion = 2;

// One dataset under /particles: its name, element type and the field it fills (an index into
// ParticleStore(dim).fields()). The reader checks a file against this list.
struct CheckpointDataset {
  std::string name;
  FieldType type;
  std::size_t field;
};
std::vector<CheckpointDataset> checkpoint_datasets(int dim, int version = kCheckpointFormatVersion);
// The exported, not checkpointed fields (derived: a restart recomputes them), one dataset per
// component. Written since spate 0.1 with format version 2; a file without them still restarts.
std::vector<CheckpointDataset> derived_datasets(int dim);
// The XDMF sidecar of a checkpoint file: checkpoint_step_N.h5 -> checkpoint_step_N.xmf2.
std::filesystem::path xdmf_sidecar(const std::filesystem::path& checkpoint);

struct CheckpointMeta {
  std::int64_t step = 0;
  double time = 0.0;
  double dt = 0.0;          // the time step the next step will take
  std::string case_name;
  std::string case_yaml;    // the effective case (after --set)
  std::string steering_log; // accepted steering changes so far (may be empty)
  int format_version = kCheckpointFormatVersion;  // of the file read (writes use the current one)
  bool derived_saved = false;  // read: the file held the derived datasets (else they are zero)
};

// `particles` must hold every particle, ordered by id.
void write_checkpoint(const std::filesystem::path& path, const CheckpointMeta& meta, ParticleStore& particles);
// The same file written one field at a time, so the particles never have to sit in one store:
// fill(k, out) writes field k of ParticleStore(dim).fields() (asked only for the datasets of
// checkpoint_datasets and derived_datasets) of all `count` particles, ordered by id, into out
// (count * elem_size bytes).
using CheckpointFieldFill = std::function<void(std::size_t field, char* out)>;
void write_checkpoint(const std::filesystem::path& path, const CheckpointMeta& meta, int dim, std::size_t count,
                      const CheckpointFieldFill& fill);
// Throws std::runtime_error naming the file and what is wrong.
CheckpointMeta read_checkpoint(const std::filesystem::path& path, ParticleStore& particles);

}  // namespace spate
