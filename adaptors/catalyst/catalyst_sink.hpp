#pragma once
// The solver's in-situ sink for ParaView Catalyst: runs Catalyst v2 Python scripts on channel
// `particles` every N steps, so that nothing a pipeline does can lose the run.
//
// Isolated (the default for a run in one process): Catalyst, Python and the scripts run in a helper
// process (insitu_helper.hpp) that maps the solver's particle memory read-only at the same address
// (zero copy; particle_memory.hpp). A script that raises is switched off (as in process); one that
// crashes the helper (segfault, abort, sys.exit, os._exit), or takes longer than `timeout` seconds
// on a step, is switched off too: the helper is killed if need be and a fresh one runs the other
// scripts from that same step on. A lost display is replaced and the step retried, with nobody to
// blame. A Live peer that never completes the handshake switches live off. Every such event is
// recorded (failures(), incidents()).
//
// In process (under MPI, where the ranks' pipelines must share the ranks' MPI world, or when asked):
// Catalyst runs in the solver process; Python errors are contained as above, crashes and hangs are
// not (docs/insitu.md).
//
// Errors: a script that is missing, or fails in the run's first in-situ step (its import,
// catalyst_initialize or first catalyst_execute), raises InSituLoadError from execute(): the run
// stops before step 1, exit 2. The live script is never a load error.
#include <atomic>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "catalyst_engine.hpp"
#include "catalyst_steering.hpp"
#include "sim/insitu.hpp"
#include "sim/steering.hpp"

class vtkMultiBlockDataSet;

namespace spate::catalyst {

struct LiveOptions {
  std::string url;                   // host:port the simulation connects out to
  std::filesystem::path script;      // pipelines/live.py
  std::filesystem::path xml;         // pipelines/spate_steering.xml
  SteeringInitial initial;           // the values the steering proxy starts with
  double handshake_timeout = 15.0;   // seconds a peer may take to answer the handshake
};

enum class Isolation { kAuto, kHelper, kInProcess };  // auto: a helper unless MPI is initialised

struct CatalystOptions {
  std::vector<std::filesystem::path> scripts;
  int every = 1;                          // steps between in-situ steps (the first step is always one)
  std::filesystem::path working_dir;      // extracts go to working_dir/<script's ExtractsOutputDirectory>
  std::vector<std::pair<std::string, double>> constants;  // field data of the dataset (dp, ...)
  std::optional<LiveOptions> live;        // Catalyst Live and steering
  double timeout = 300.0;                 // seconds one script may take on one step (isolated)
  Isolation isolation = Isolation::kAuto;
  std::filesystem::path helper_program;   // the spate binary (default: this program)
};

// Time spent per in-situ step, for the performance report.
struct InSituTiming {
  std::int64_t steps = 0;                 // in-situ steps executed
  double adaptor_seconds = 0.0;           // building/refreshing the dataset (sum over steps)
  std::vector<double> adaptor_step_seconds;  // the same, step by step (the first one allocates)
  double pipelines_seconds = 0.0;         // the pipelines' own work, all scripts (sum over steps)
  std::vector<double> pipelines_step_seconds;  // the same, step by step (the first one imports the scripts)
  std::vector<double> script_seconds;     // per script, same order as the options (live.py last)
  // What the solver waited for each in-situ step: the above plus, isolated, the round trip to the
  // helper (and any restart of it).
  std::vector<double> solver_wait_step_seconds;
};

class CatalystSink final : public InSituSink {
 public:
  // Checks the scripts exist and starts Catalyst (the helper, or in process). Throws
  // InSituLoadError.
  explicit CatalystSink(CatalystOptions options);
  ~CatalystSink() override;  // finalises Catalyst (before MPI_Finalize, as OpenMPI requires)
  CatalystSink(const CatalystSink&) = delete;
  CatalystSink& operator=(const CatalystSink&) = delete;

  bool wants(std::int64_t step, double time) override;
  void execute(std::int64_t step, double time, const std::vector<SlabView>& slabs) override;
  std::vector<std::string> failures() const override;
  void set_interval(int every) override;  // steering: insitu_every (>= 1)

  // Steering requests from the live client (null without live).
  SteeringSource* steering();
  bool isolated() const;
  InSituTiming timing() const;
  // What went wrong and was recovered from (a lost display replaced), for insitu.json.
  std::vector<std::string> incidents() const;
  // For tests, in process only: the dataset as last handed to the pipelines (null before).
  vtkMultiBlockDataSet* last_dataset() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace spate::catalyst
