#pragma once
// The time loop: sets up the slabs (one worker thread per device), runs steps, reduces the time
// step, samples probes, writes snapshots, checkpoints and the summary. Bad input (exit 2) is
// thrown before the output folder exists; anything that happens after it ends in a RunResult
// (done, unstable, interrupted, or the failure of an output, of memory or of the code), so that a
// summary.json can always be written.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "../case/case.hpp"
#include "../backend/pass_times.hpp"
#include "../case/generator.hpp"
#include "steering.hpp"
#include "insitu.hpp"

namespace spate {

struct RunOptions {
  std::filesystem::path out_dir;
  std::optional<std::int64_t> steps;      // run this many steps (from the start or the restart)
  std::optional<double> until;            // or until this simulated time (default: the case's end)
  int threads = 0;                        // 0: all hardware threads
  int devices = 1;                        // slabs in this process
  std::string backend = "cpu";            // "cpu" or "cuda" (one GPU per device worker)
  std::optional<int> checkpoint_every;    // overrides the case's output.checkpoint_every
  std::optional<std::filesystem::path> restart;
  bool quiet = false;
  std::optional<int> checkpoint_keep_last;   // overrides output.checkpoint_keep_last (the newest kept; 0: all)
  std::optional<int> checkpoint_keep_every;  // overrides output.checkpoint_keep_every (every Nth kept for good)
  SteeringSource* steering = nullptr;     // live requests or a replayed log; polled every step
  InSituSink* insitu = nullptr;           // in-situ consumer (Catalyst), asked at the start and after every step
};

struct RunResult {
  int exit_code = 0;                      // 0 done, 3 unstable, 4 internal error, 5 output failed, 6 out of memory, 128 + signal
  std::string exit_status = "done";       // "done" | "unstable" | "internal_error" | "output_failed" | "out_of_memory" | "interrupted"
  std::string message;
  std::int64_t steps = 0;                 // steps taken in this run
  std::int64_t final_step = 0;
  double simulated_time = 0.0;
  double wall_seconds = 0.0;
  double stepping_seconds = 0.0;  // the time loop alone: no final checkpoint, no summary
  ParticleCounts particles;
  std::filesystem::path last_checkpoint;
  std::vector<std::int64_t> slab_particles;
  std::vector<double> slab_busy_seconds;    // per slab: time in its own neighbour loops
  std::vector<PassSeconds> slab_pass_seconds;  // per slab and pass (SPATE_PASS_TIMERS=1; else empty)
  double imbalance = 1.0;
  std::int64_t ghosts = 0;
  double bytes_per_particle = 0.0;         // solver arrays (owned + ghosts + cell grid) / particles
  std::vector<double> imbalance_history;   // max/mean before each balancing pass
  std::int64_t migrated = 0;               // particles that crossed a slab face by moving
  std::int64_t handed_over = 0;            // particles handed to a new owner because faces moved
  std::int64_t face_moves = 0;             // balancing passes that moved faces
  std::vector<std::string> insitu_failures;
  std::int64_t steering_accepted = 0, steering_rejected = 0;
  bool stopped_by_steering = false;
  std::int64_t removed = 0;                       // fluid removed through open sides, since t = 0
  std::vector<std::uint32_t> removed_first_ids;   // the first few of them
  std::int64_t closed_volume_scalings = 0;        // density.closed_volume: steps whose densities were scaled back
};

class Simulation {
 public:
  Simulation(Case c, RunOptions options);
  RunResult run();

 private:
  Case case_;
  RunOptions options_;
};

// Error for bad command-line or restart input (exit 2), distinct from case-file errors only in text.
struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Asks a running simulation to stop at the next step boundary, write its final checkpoint and
// summary and end with exit code 128 + signal (async-signal-safe: the SIGINT/SIGTERM handler).
void request_stop(int signal) noexcept;

}  // namespace spate
