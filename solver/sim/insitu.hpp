#pragma once
// What the solver shows to in-situ consumers (the Catalyst adaptor): a read-only view of each
// local slab's owned particles, pointing straight at solver memory. The solver knows nothing of VTK.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace spate {

struct SlabView {
  int slab = 0;             // global slab (device) index
  int slab_count = 1;
  int dim = 3;
  std::size_t owned = 0;    // particles [0, owned) of every array
  const float* pos[3] = {nullptr, nullptr, nullptr};  // pos[2] is null in 2D
  const float* vel[3] = {nullptr, nullptr, nullptr};
  const float* pressure = nullptr;
  const float* density = nullptr;
  const std::uint32_t* id = nullptr;
  const std::uint8_t* kind = nullptr;
};

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
