#pragma once
// What the solver shows to in-situ consumers (the Catalyst adaptor): a read-only view of each
// local slab's owned particles, pointing straight at solver memory. The solver knows nothing of VTK.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "../case/case.hpp"
#include "../particles/field_registry.hpp"
#include "../physics/materials.hpp"

namespace spate {

// One exported field of the registry (kExported, field_registry.hpp) as consumers see it.
struct SlabArray {
  std::string_view name;     // the exported name ("velocity", "pressure", "density", "id", "kind", ...)
  FieldType type;
  int components = 1;        // 3 for vectors (components beyond dim are null), 1 for scalars
  const void* data[3] = {nullptr, nullptr, nullptr};
  template <class T>
  const T* values(int component = 0) const {
    return static_cast<const T*>(data[component]);
  }
};

struct SlabView {
  int slab = 0;             // global slab (device) index
  int slab_count = 1;
  int dim = 3;
  std::size_t owned = 0;    // particles [0, owned) of every array
  int fluids = 1;           // materials [0, fluids) are fluids (phases); > 1: consumers add `phase`
  const float* pos[3] = {nullptr, nullptr, nullptr};  // the points; pos[2] is null in 2D
  std::vector<SlabArray> arrays;  // every other exported field, in registry order
  const SlabArray* array(std::string_view name) const {
    for (const SlabArray& a : arrays)
      if (a.name == name) return &a;
    return nullptr;
  }
};

class ParticleStore;
// The view of a slab's owned particles [0, owned): every exported field of the registry, pointing
// at the store's arrays (zero copy; valid until the store next changes). `fluids`: the case's fluid
// count (several fluids: snapshots and Catalyst add the derived array `phase`,
// phase_of in materials.hpp).
SlabView slab_view(ParticleStore& p, int slab, int slab_count, int fluids = 1);


// Case constants that pipelines read from the dataset's field data (sprite sizes, interpolation
// kernels): put there in situ by the Catalyst adaptor and into every snapshot's .vtm, so that a
// pipeline finds them in both.
std::vector<std::pair<std::string, double>> case_constants(const Case& c);

class InSituSink {
 public:
  virtual ~InSituSink() = default;
  // Whether step/time is an in-situ step (same answer on every rank).
  virtual bool wants(std::int64_t step, double time) = 0;
  // Called once per process on in-situ steps with all of its local slabs. Errors inside a pipeline
  // are the sink's to report; it must not throw for them.
  virtual void execute(std::int64_t step, double time, const std::vector<SlabView>& slabs) = 0;
  // Pipeline failures to put in summary.json.
  virtual std::vector<std::string> failures() const { return {}; }
  // Steering (insitu_every): steps between in-situ steps from now on. Called with the same value
  // by every slab at a step boundary.
  virtual void set_interval(int /*every*/) {}
};

}  // namespace spate
