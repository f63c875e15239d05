#pragma once
// Fluid features too thin for the chosen particle spacing. A layer of water needs about three
// particle layers to behave as a fluid (a kernel support of 2h = 2.6 dp across it): thinner, it
// dewets into holes or, below half a dp, gets no particles at all. spate info and spate run warn
// about the wet bed, every fluid block's thinnest extent and every gap between a solid and a wall
// or another solid that is thinner than three layers, and say which dp resolves it.
#include <string>
#include <vector>

#include "case.hpp"

namespace spate {

inline constexpr double kMinFeatureLayers = 3.0;

struct ThinFeature {
  std::string key;         // the case key it comes from: "wet_bed", "fluid_blocks[1]", "solids[0]"
  std::string what;        // "the wet bed is 0.01 m deep", "the gap between solid 'post' and the tank wall at x = 0 is 0.02 m wide"
  double thickness = 0.0;  // m
  double layers = 0.0;     // thickness / dp
  double resolving_dp = 0.0;  // the largest dp that gives it three layers: thickness / 3
  std::string message(double dp) const;
};

std::vector<ThinFeature> thin_features(const Case& c);

}  // namespace spate
