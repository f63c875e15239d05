#pragma once
// The subcommands of the spate program, each a thin layer over the solver library.
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace spate {
struct Case;
namespace catalyst {
class CatalystSink;
struct CatalystOptions;
}
}  // namespace spate

namespace spate::app {

struct BadInput : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct RunArgs {
  std::string case_file, out, backend = "cpu", restart, live, steering_log;
  std::optional<long long> steps;
  std::optional<double> until;
  std::vector<std::string> overrides, pipelines;
  int threads = 0, devices = 1;
  std::optional<int> checkpoint_every, checkpoint_keep_last, checkpoint_keep_every, insitu_every;
  bool quiet = false;
  bool live_requested = false;  // --live given (with or without an address)
};
struct InfoArgs {
  std::string case_file, backend = "cpu";
  std::vector<std::string> overrides;
  int devices = 1;
  bool json = false;
};
struct CompareArgs {
  std::string a, b;
  double tolerance = 0.0;
  std::optional<double> scaled_tolerance;  // per field: this times field_scale (io/field_scale.hpp)
};
struct BenchArgs {
  std::string case_file, backend = "cpu";
  std::vector<std::string> overrides;
  int steps = 10, threads = 0, devices = 1;
  bool json = false, pass_times = false;
};

struct PostArgs {
  std::string run_dir, out, from;
  std::vector<std::string> probes, pipelines;
  std::vector<long long> steps;  // saved steps to use (empty: all)
  int threads = 0;
  bool plot = false;
};
struct PlotArgs {
  std::string dir, out;
};
struct GrowthArgs {
  std::string csv, column = "amplitude";
  std::optional<double> until;
  bool json = false;
};

int run_command(const RunArgs& a);
int post_command(const PostArgs& a);
int plot_command(const PlotArgs& a);
int growth_command(const GrowthArgs& a);
int info_command(const InfoArgs& a);
int compare_command(const CompareArgs& a);
int bench_command(const BenchArgs& a);

// Shared by the commands.
int hardware_threads();
// The environment variables spate reads (SPATE_PASS_TIMERS, SPATE_GPU_PAIR_LOOP,
// SPATE_CUDA_HALO_LINK), checked before any work: a bad value is bad input (BadInput, exit 2).
void check_environment();
// spate's data files (pipelines/, scripts/): $SPATE_DATA_DIR, else <prefix>/share/spate for an
// installed spate (cmake --install), else the source tree it was built from.
std::filesystem::path data_dir();
#ifdef SPATE_WITH_CATALYST
// A Catalyst sink for `co` (scripts, every, working_dir, live) with the case's constants in the
// dataset's field data and its insitu.timeout; working_dir is created. A script that fails to
// load: BadInput.
std::unique_ptr<catalyst::CatalystSink> make_catalyst_sink(catalyst::CatalystOptions co, const Case& c);
#endif

}  // namespace spate::app
