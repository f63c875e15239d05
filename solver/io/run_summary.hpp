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
std::int64_t peak_rss_bytes();

}  // namespace spate
