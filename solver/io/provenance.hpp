#pragma once
// Where a result came from, for summary.json: the command line and start time of this process,
// the host, UTC timestamps and file digests. The program records its command line once at start.
#include <filesystem>
#include <string>
#include <vector>

namespace spate {

struct Provenance {
  std::vector<std::string> command_line;  // argv as given
  std::string host;
  std::string start_time;  // ISO 8601, UTC (2024-05-01T12:34:56Z)
};

// Records argv, the host and the start time (main() calls it first thing).
void record_invocation(int argc, const char* const* argv);
const Provenance& invocation();

std::string utc_timestamp();  // now, ISO 8601 UTC
// SHA-256 of a file's bytes as lowercase hex (what `sha256sum FILE` prints); empty if unreadable.
std::string sha256_of_file(const std::filesystem::path& path);

}  // namespace spate
