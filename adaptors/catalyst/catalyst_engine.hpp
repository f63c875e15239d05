#pragma once
// ParaView Catalyst in this process (legacy vtkCPProcessor API, as Debian's ParaView 5.11 ships it),
// running Catalyst v2 Python scripts on channel `particles`. Used by the in-situ helper process
// (the normal case, insitu_helper.hpp) and directly by the solver process under MPI (where the
// ranks' pipelines must run in the ranks' own MPI world).
//
// Construct it and call run_step() on the process's main thread: VTK's garbage collector asserts
// it runs there, and Debian's ParaView Python is not built thread-safe.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <set>
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

struct EngineOptions {
  std::vector<std::filesystem::path> scripts;  // absolute paths
  std::vector<int> ids;                        // how the scripts are named in reports (default 0, 1, ...)
  std::filesystem::path working_dir;           // extracts go to working_dir/<script's ExtractsOutputDirectory>
  // Case constants put in the dataset's field data (e.g. "dp", "smoothing_length"), so that
  // scripts can size sprites and interpolation kernels without knowing the case.
  std::vector<std::pair<std::string, double>> constants;
  bool mpi = false;  // initialise Catalyst with MPI_COMM_WORLD (MPI must be initialised)
};

struct ScriptFailure {
  int id = 0;
  std::string error;  // ParaView's and Python's text (the traceback)
};

struct EngineStep {
  bool ran = false;               // some script asked for the data
  double adaptor_seconds = 0.0;   // building/refreshing the dataset
  std::vector<std::pair<int, double>> script_seconds;  // id -> seconds of its own work this step
  std::vector<ScriptFailure> failures;                 // scripts that failed this step (now removed)
};

// Told whenever a script starts working (asking for data, importing, running) and when it is done
// for the step (the helper reports both to the solver process, which blames a crash or a hang on
// the script that started last and had not finished).
struct ScriptObserver {
  virtual ~ScriptObserver() = default;
  virtual void started(int id) = 0;
  virtual void finished(int id) = 0;
};

class CatalystEngine {
 public:
  // Starts Catalyst and prepares the scripts; throws InSituLoadError when Catalyst cannot start or
  // ParaView cannot prepare a script.
  explicit CatalystEngine(EngineOptions options);
  ~CatalystEngine();  // finalises Catalyst (before MPI_Finalize, as OpenMPI requires)
  CatalystEngine(const CatalystEngine&) = delete;
  CatalystEngine& operator=(const CatalystEngine&) = delete;

  // One in-situ step over the slabs' views: the scripts in `skip` sit it out. A script that fails
  // (a Python error) is reported in the result and removed; the others go on.
  EngineStep run_step(std::int64_t step, double time, const std::vector<SlabView>& slabs, const std::set<int>& skip = {},
                      ScriptObserver* observer = nullptr);
  bool empty() const;  // no script left
  // For tests: the dataset as last handed to the pipelines (null before the first step).
  vtkMultiBlockDataSet* last_dataset() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace spate::catalyst
