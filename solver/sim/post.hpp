#pragma once
// After the run (spate post): the steps a run saved, read back, and the run's own probe code
// applied to them. A saved step holds every particle with the fields a probe reads (positions,
// velocities, densities, pressures as the run had them, material), so a probe sampled on it gives
// exactly the value the run wrote at that step, and probes defined after the run come for free.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "../case/case.hpp"
#include "../case/motion.hpp"
#include "../io/vtk_snapshot.hpp"
#include "../particles/particle_store.hpp"
#include "probes.hpp"
#include "steering.hpp"

namespace spate {

enum class SavedKind { Snapshot, Checkpoint };

// One saved step of a run folder: a snapshot listed in particles.pvd, or a checkpoint.
struct SavedStep {
  SavedKind kind = SavedKind::Snapshot;
  std::filesystem::path file;  // the .vtm or the .h5
  std::int64_t step = 0;       // from the file name (step_NNNNNNNN)
  double time = 0.0;           // snapshots: from particles.pvd (checkpoints: read with the file)
};
// The run's snapshots (in particles.pvd order) or checkpoints (by step), oldest first.
std::vector<SavedStep> saved_steps(const std::filesystem::path& run_dir, SavedKind kind);

// A saved step's particles, one store per slab piece (a checkpoint is one piece).
struct SavedState {
  double time = 0.0;
  std::int64_t step = 0;
  std::vector<ParticleStore> pieces;
  std::vector<int> slabs;      // each piece's slab (block) index
  int slab_count = 1;
  bool derived_saved = true;   // pressures (and wall states) as the run had them; false: an old checkpoint without them
  std::string case_yaml;       // checkpoints: the effective case they hold (else empty)
  std::string bodies;          // checkpoints: the floating solids' state (RigidBodies::save()'s text)
  FieldData field_data;        // snapshots: their field data (the floating solids' state among it)
};
// Throws std::runtime_error naming the file.
SavedState load_saved(const SavedStep& s, int dim);

// The case of a run folder: its case.yaml, else the case a checkpoint holds. Throws CaseError.
// `overrides` are applied as with --set.
Case run_case(const std::filesystem::path& run_dir, const std::vector<std::string>& overrides = {});

// Samples the case's probes on saved states into <out_dir>/probes/<name>.csv (the run's format).
// `steering`: the run's accepted changes (its steering.log); the changes of a wall motion are
// replayed, so that moving walls and the probes that follow them are where the run had them.
class SavedProbes {
 public:
  SavedProbes(const Case& c, const std::filesystem::path& out_dir, const std::vector<SteeringChange>& steering = {});
  ~SavedProbes();
  // Returns the rows as ProbeSet::sample does. Old checkpoints without the saved pressures get
  // them recomputed from the densities (close to, not exactly, the run's values).
  std::vector<std::vector<double>> sample(const SavedState& s);

 private:
  const Case& case_;
  ProbeSet probes_;
  MotionSet motions_;
};

}  // namespace spate
