#pragma once
// The source tree the tests read cases and pipelines from: $SPATE_SOURCE_DIR when it is set (a
// build carried to another machine, e.g. by scripts/gpu-pack, where the tree sits elsewhere),
// else the tree the build was configured from (the compile definition SPATE_SOURCE_DIR).
#include <cstdlib>
#include <string>

namespace spate::test {

inline std::string source_dir() {
  if (const char* dir = std::getenv("SPATE_SOURCE_DIR"); dir != nullptr && *dir != '\0') return dir;
  return SPATE_SOURCE_DIR;
}

}  // namespace spate::test
