#pragma once
// The ParaView Catalyst adaptor (legacy vtkCPProcessor API, as Debian's ParaView 5.11 ships it):
// runs Catalyst v2 Python scripts on channel `particles` every N steps.
//
// Construct it, and let the simulation call execute(), on the process's main thread: VTK's
// garbage collector asserts it runs there, and Debian's ParaView Python is not built thread-safe.
// (Simulation runs its first local slab, the one that calls execute(), on the calling thread.)
//
// Errors: a script that is missing, or fails on its first run (import, catalyst_initialize or the
// first catalyst_execute), raises InSituLoadError (the run stops before step 1, exit 2). A script
// that fails later is switched off with its traceback kept in failures(); the run goes on.
#include <atomic>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "sim/insitu.hpp"
#include "sim/simulation.hpp"

class vtkMultiBlockDataSet;

namespace spate::catalyst {

// Bad in-situ input (a script missing or failing to load): exit 2, like any bad input.
struct InSituLoadError : InputError {
  using InputError::InputError;
};

struct CatalystOptions {
  std::vector<std::filesystem::path> scripts;
  int every = 1;                          // steps between in-situ steps (the first step is always one)
  std::filesystem::path working_dir;      // extracts go to working_dir/<script's ExtractsOutputDirectory>
  // Case constants put in the dataset's field data (e.g. "dp", "smoothing_length"), so that
  // scripts can size sprites and interpolation kernels without knowing the case.
  std::vector<std::pair<std::string, double>> constants;
};

// Time spent per in-situ step, for the performance report.
struct InSituTiming {
  std::int64_t steps = 0;                 // in-situ steps executed
  double adaptor_seconds = 0.0;           // building/refreshing the dataset (sum over steps)
  std::vector<double> adaptor_step_seconds;  // the same, step by step (the first one allocates)
  double pipelines_seconds = 0.0;         // the pipelines' own work, all scripts (sum over steps)
  std::vector<double> pipelines_step_seconds;  // the same, step by step (the first one imports the scripts)
  std::vector<double> script_seconds;     // per script, same order as the options
};

class CatalystSink final : public InSituSink {
 public:
  // Checks the scripts exist and starts Catalyst (MPI-aware when MPI is initialised). Throws
  // InSituLoadError.
  explicit CatalystSink(CatalystOptions options);
  ~CatalystSink() override;  // finalises Catalyst (before MPI_Finalize, as OpenMPI requires)
  CatalystSink(const CatalystSink&) = delete;
  CatalystSink& operator=(const CatalystSink&) = delete;

  bool wants(std::int64_t step, double time) override;
  void execute(std::int64_t step, double time, const std::vector<SlabView>& slabs) override;
  std::vector<std::string> failures() const override;
  void set_interval(int every) override;  // steering: insitu_every (>= 1)

  InSituTiming timing() const;
  // For tests: the dataset as last handed to the pipelines (null before the first step).
  vtkMultiBlockDataSet* last_dataset() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace spate::catalyst
