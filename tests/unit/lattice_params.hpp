#pragma once
// The physics of a small case for the pair-term tests, which evaluate their terms on hand-made
// particle lattices: dp = 0.01 m unless given, Wendland C2, one fluid (a 0.1 m block in a 0.2 m tank
// in 3D, 0.4 m in 2D), with `options` (YAML) added: the keys under test.
#include <string>

#include "case/case.hpp"

namespace spate {

inline PhysicsParams lattice_params(int dim, const std::string& options = "", double dp = 0.01) {
  const std::string head = "name: lattice\ndimensions: " + std::to_string(dim) + "\ndp: " + std::to_string(dp) + "\ntime:\n  end: 0.1\n";
  const std::string yaml = head + (dim == 3 ? "tank:\n  size: [0.2, 0.2, 0.2]\n"
                                              "fluid_blocks:\n  - min: [0, 0, 0]\n    max: [0.1, 0.1, 0.1]\n"
                                            : "tank:\n  size: [0.4, 0.4]\n"
                                              "fluid_blocks:\n  - min: [0, 0]\n    max: [0.1, 0.1]\n");
  return physics_params(parse_case(yaml + options, "lattice.yaml"));
}

}  // namespace spate
