#pragma once
// HDF5 checkpoints: the global particle state ordered by id (independent of how the run was split)
// plus the step, time, next time step and the case text, so a restart continues bit-identically
// with any number of devices or ranks. Writes go to a temporary file that is renamed into place:
// a run killed mid-write leaves the previous checkpoint intact.
//
// A checkpoint is input like a case file, and is read as such (docs/cli.md, checkpoints): every
// attribute and dataset is checked (type, rank, length, storage) before anything is allocated,
// every dataset carries HDF5's Fletcher32 checksum and the header a checksum of its own, and the
// values are checked after reading (finite, inside the domain, known materials, ids unique and in
// range); the case it embeds must be a valid case, and for a restart of the same geometry as the
// run's case. Anything wrong is a CheckpointError naming the file, the attribute or dataset and
// the reason.
//
// Beside the restart state a checkpoint holds the exported fields a restart recomputes (pressure),
// as they were at that step, so that it shows exactly what a snapshot of the step would
// (spate post evaluates probes on it), and an XDMF sidecar (<name>.xmf2, next to <name>.h5) that
// ParaView's XDMF reader opens: the particles as vertices with every exported field.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "../case/case.hpp"
#include "../particles/particle_store.hpp"
#include "../sim/steering.hpp"

namespace spate {

// Version 3: every dataset with HDF5's Fletcher32 checksum, a header checksum, the geometry hash of
// the case and the count of particles removed through open sides. Version 2 (still read, without
// those checks): the material index dataset is "material"; version 1 (also read), before the field
// registry, called it "kind". The datasets themselves follow the field registry (every
// kCheckpointed field, one dataset per component).
constexpr int kCheckpointFormatVersion = 3;

// One dataset under /particles: its name, element type and the field it fills (an index into
// ParticleStore(dim).fields()). The reader checks a file against this list.
struct CheckpointDataset {
  std::string name;
  FieldType type;
  std::size_t field;
};
std::vector<CheckpointDataset> checkpoint_datasets(int dim, int version = kCheckpointFormatVersion);
// The exported, not checkpointed fields (derived: a restart recomputes them), one dataset per
// component. Written since format version 2; a file without them still restarts.
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
  // Read: steering_log parsed and checked as a live change is (no step after `step`, fluids of
  // the case); what a restart replays. Not written (steering_log is the file's form).
  std::vector<SteeringChange> steering_history;
  std::int64_t removed = 0;  // fluid particles removed through open sides before this step
  // The floating solids' state and last loads (RigidBodies::save; empty without them): attribute
  // `bodies`, part of the header checksum when there is one.
  std::string bodies;
  // A driven flow's state (FlowDrive::save; empty without `drive`): attribute `drive`, part of the
  // header checksum when there is one.
  std::string drive;
  // A held volume's reference (ClosedVolume::save; empty without `density.closed_volume`): attribute
  // `closed_volume`, part of the header checksum when present.
  std::string closed_volume;
  std::string geometry_hash;  // geometry_hash() of the case (generator.hpp); empty before version 3
  int format_version = kCheckpointFormatVersion;  // of the file read (writes use the current one)
  bool derived_saved = false;  // read: the file held the derived datasets (else they are zero)
};

struct CheckpointError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// `particles` must hold every particle, ordered by id. Write failures throw OutputError.
void write_checkpoint(const std::filesystem::path& path, const CheckpointMeta& meta, ParticleStore& particles);
// The same file written one field at a time, so the particles never have to sit in one store:
// fill(k, out) writes field k of ParticleStore(dim).fields() (asked only for the datasets of
// checkpoint_datasets and derived_datasets) of all `count` particles, ordered by id, into out
// (count * elem_size bytes).
using CheckpointFieldFill = std::function<void(std::size_t field, char* out)>;
void write_checkpoint(const std::filesystem::path& path, const CheckpointMeta& meta, int dim, std::size_t count,
                      const CheckpointFieldFill& fill);
// Reads and checks a checkpoint (see above). With `run_case` (a restart), the checkpoint must hold
// that case's geometry, and its positions must lie in that case's domain. Throws CheckpointError.
CheckpointMeta read_checkpoint(const std::filesystem::path& path, ParticleStore& particles, const Case* run_case = nullptr);

}  // namespace spate
