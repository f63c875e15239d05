#pragma once
// Helpers for integration tests that drive the solver library directly.
#include <cstdio>
#include <cstring>
#include <functional>
#include <filesystem>
#include <string>
#include <vector>

#include "../source_dir.hpp"
#include "case/case.hpp"
#include "io/checkpoint.hpp"
#include "sim/simulation.hpp"

namespace spate::test {

inline std::string case_path(const std::string& name) { return test::source_dir() + "/cases/" + name; }

// A fresh folder for a test's output, named after the test and the checkout it was built from, so
// that two checkouts running the same test at once (engineers' worktrees, a merge being tested) do
// not write into each other's folders.
inline std::filesystem::path scratch(const std::string& name) {
  const auto checkout = std::hash<std::string>{}(test::source_dir()) % 0x100000000ull;
  char tag[16];
  std::snprintf(tag, sizeof tag, "%08llx", static_cast<unsigned long long>(checkout));
  auto p = std::filesystem::temp_directory_path() / ("spate-test-" + std::string(tag) + "-" + name);
  std::filesystem::remove_all(p);
  return p;
}

inline RunResult run_case(const Case& c, const std::filesystem::path& out, RunOptions o = {}) {
  o.out_dir = out;
  o.quiet = true;
  if (o.threads == 0) o.threads = 1;
  return Simulation(c, o).run();
}

// True when both checkpoints hold bit-identical particle fields.
inline bool identical_checkpoints(const std::filesystem::path& a, const std::filesystem::path& b, std::string* why = nullptr) {
  ParticleStore pa, pb;
  read_checkpoint(a, pa);
  read_checkpoint(b, pb);
  if (pa.size() != pb.size()) {
    if (why) *why = "particle counts differ";
    return false;
  }
  auto fa = pa.fields(), fb = pb.fields();
  for (std::size_t f = 0; f < fa.size(); ++f) {
    if (!fa[f].has(kCheckpointed)) continue;
    if (std::memcmp(fa[f].bytes(), fb[f].bytes(), pa.size() * fa[f].elem_size) != 0) {
      if (why) *why = "field " + std::string(fa[f].name) + " differs";
      return false;
    }
  }
  return true;
}

// Column `col` of a probe CSV (header line, then time,step,values...) as (time, value) pairs.
std::vector<std::pair<double, double>> read_probe(const std::filesystem::path& csv, int col);
// Mean of column `col` of a probe CSV over the rows with time > from (NaN when there are none).
double mean_after(const std::filesystem::path& csv, int col, double from);

}  // namespace spate::test
