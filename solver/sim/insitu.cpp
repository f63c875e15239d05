#include "insitu.hpp"

#include "../particles/particle_store.hpp"

namespace spate {

SlabView slab_view(ParticleStore& p, int slab, int slab_count, int fluids) {
  SlabView v;
  v.fluids = fluids;
  v.slab = slab;
  v.slab_count = slab_count;
  v.dim = p.dim();
  v.owned = p.owned();
  for (const ExportedField& f : exported_fields(p)) {
    if (f.spec->member == "pos") {
      for (int k = 0; k < f.components; ++k) v.pos[k] = reinterpret_cast<const float*>(f.data[k]);
      continue;
    }
    SlabArray a{f.spec->exported, f.spec->type, f.spec->shape == FieldShape::Vector ? 3 : 1, {}};
    for (int k = 0; k < f.components; ++k) a.data[k] = f.data[k];
    v.arrays.push_back(a);
  }
  return v;
}

std::vector<std::pair<std::string, double>> case_constants(const Case& c) {
  const PhysicsParams P = physics_params(c);
  return {{"dimensions", c.dim}, {"dp", c.dp}, {"smoothing_length", P.h}, {"rest_density", c.fluids[0].density},
          {"particle_mass", P.materials.fluid[0].mass}, {"fluids", static_cast<double>(c.fluids.size())}};
}

}  // namespace spate
