#pragma once
// summary.json: the machine-readable record of a run. Scripts read these names; keep them stable
// (docs/cli.md lists them).
#include <filesystem>
#include <string>
#include <vector>

#include "../case/case.hpp"
#include "../sim/simulation.hpp"

namespace spate {

struct SummaryExtras {
  int threads = 1;
  int devices = 1;
  int ranks = 1;
  std::string backend = "cpu";
  std::vector<std::string> warnings;  // what the run warned about before it started (thin features)
};

void write_summary(const std::filesystem::path& path, const Case& c, const PhysicsParams& P, const RunResult& r,
                   const SummaryExtras& extras);
// The summary of a run that ended before its simulation started (bad input, exit 2, or an
// internal error): the case as far as it was read (name empty when the file did not parse), the
// provenance, exit_status, exit_code and message; none of the run's fields.
void write_refusal_summary(const std::filesystem::path& path, const std::string& case_name, const std::string& case_file,
                           const std::string& exit_status, int exit_code, const std::string& message);
std::int64_t peak_rss_bytes();

}  // namespace spate
