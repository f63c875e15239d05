#include "thin_features.hpp"

#include <fmt/format.h>


namespace spate {

namespace {

const char* const kAxis[3] = {"x", "y", "z"};

bool overlaps_across(const Box& a, const Box& b, int dim, int axis) {
  for (int k = 0; k < dim; ++k)
    if (k != axis && (a.max[k] <= b.min[k] || b.max[k] <= a.min[k])) return false;
  return true;
}

}  // namespace

std::string ThinFeature::message(double dp) const {
  // Lattice sites sit at (i + 1/2) dp: under half a dp a feature gets no particles at all.
  const char* effect = layers < 0.5 ? "it gets no particles" : "too thin to behave as water";
  return fmt::format("{}: {}: {:.2g} particle layers at dp = {:g} m, fewer than {:g} ({}); dp <= {:.3g} m resolves it", key,
                     what, layers, dp, kMinFeatureLayers, effect, resolving_dp);
}

std::vector<ThinFeature> thin_features(const Case& c) {
  const int d = c.dim, v = d - 1;
  std::vector<ThinFeature> out;
  auto consider = [&](std::string key, std::string what, double thickness) {
    if (!(thickness > 0) || thickness >= kMinFeatureLayers * c.dp * (1 - 1e-9)) return;
    out.push_back({std::move(key), std::move(what), thickness, thickness / c.dp, thickness / kMinFeatureLayers});
  };
  if (c.wet_bed > 0) consider("wet_bed", fmt::format("the wet bed is {:g} m deep", c.wet_bed), c.wet_bed);
  for (std::size_t b = 0; b < c.fluid_blocks.size(); ++b) {
    const Box& box = c.fluid_blocks[b];
    int thin = 0;
    for (int k = 1; k < d; ++k)
      if (box.max[k] - box.min[k] < box.max[thin] - box.min[thin]) thin = k;
    const double t = box.max[thin] - box.min[thin];
    consider(fmt::format("fluid_blocks[{}]", b), fmt::format("the block is {:g} m thick along {}", t, kAxis[thin]), t);
  }
  // Gaps around each solid, along each axis: to the tank wall or to the nearest solid facing it
  // (two solids' gap is reported once, from the solid on its upper side). Above a solid under an
  // open top there is no gap.
  for (std::size_t s = 0; s < c.solids.size(); ++s) {
    const Box& box = c.solids[s].box;
    for (int a = 0; a < d; ++a) {
      const double wall_lo = c.tank_origin[a], wall_hi = c.tank_origin[a] + c.tank_size[a];
      double lo = box.min[a] - wall_lo;
      std::string lo_what = fmt::format("the tank wall at {} = {:g}", kAxis[a], wall_lo);
      for (std::size_t o = 0; o < c.solids.size(); ++o) {
        const Box& other = c.solids[o].box;
        if (o == s || other.max[a] > box.min[a] || !overlaps_across(box, other, d, a)) continue;
        if (box.min[a] - other.max[a] < lo) lo = box.min[a] - other.max[a], lo_what = fmt::format("solid '{}'", c.solids[o].name);
      }
      consider(fmt::format("solids[{}]", s), fmt::format("the gap along {} between solid '{}' and {} is {:g} m wide", kAxis[a], c.solids[s].name, lo_what, lo), lo);
      if (a == v && c.open_top) continue;
      const double hi = wall_hi - box.max[a];
      // Only a wall counts here: a solid above this one reports the gap from its own lower side.
      bool solid_between = false;
      for (std::size_t o = 0; o < c.solids.size(); ++o) {
        const Box& other = c.solids[o].box;
        if (o != s && other.min[a] >= box.max[a] && overlaps_across(box, other, d, a)) solid_between = true;
      }
      if (!solid_between)
        consider(fmt::format("solids[{}]", s),
                 fmt::format("the gap along {} between solid '{}' and the tank wall at {} = {:g} is {:g} m wide", kAxis[a], c.solids[s].name,
                             kAxis[a], wall_hi, hi),
                 hi);
    }
  }
  return out;
}

}  // namespace spate
