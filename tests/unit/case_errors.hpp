#pragma once
// The error a case's YAML (with --set overrides) is rejected with, or "(no error)": the loader tests'
// way of checking that bad input names the file, the key and the reason.
#include <string>
#include <vector>

#include "case/case.hpp"

namespace spate::test {

inline std::string error_of(const std::string& yaml, const std::vector<std::string>& overrides = {}) {
  try {
    parse_case(yaml, "case.yaml", overrides);
  } catch (const CaseError& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace spate::test
