#pragma once
// The subcommands of the spate program, each a thin layer over the solver library.
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

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
  bool json = false;
};

int run_command(const RunArgs& a);
int info_command(const InfoArgs& a);
int compare_command(const CompareArgs& a);
int bench_command(const BenchArgs& a);

}  // namespace spate::app
