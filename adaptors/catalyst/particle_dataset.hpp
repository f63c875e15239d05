#pragma once
// The dataset handed to Catalyst on channel `particles`: a vtkMultiBlockDataSet with one block per
// device (slab), each a vtkPolyData of the slab's owned particles. On the CPU backend every
// per-particle array wraps solver memory (zero copy); only the arrays a pipeline asks for are made.
//
// Block k (of slab_count, the same on every rank; blocks of other ranks are null) holds:
//   points    x, y, z     vtkSOADataArrayTemplate<float> over the solver's three position arrays;
//                         in 2D, z is a shared array of zeros (the solver has no z)
//   every exported field of the field registry (solver/particles/field_registry.hpp), under its
//   exported name, wrapping the solver array: vectors as vtkSOADataArrayTemplate<float> with 3
//   components (z = 0 in 2D), float scalars as vtkFloatArray, uint32 as vtkUnsignedIntArray,
//   uint8 as vtkUnsignedCharArray. Today: velocity, density, pressure, id, kind (the material
//   index: 0 fluid, 1 tank wall, 2 + k solid k).
//   device    int32       the owning slab index (a constant array kept by the adaptor)
//   verts     one vertex cell per particle (connectivity kept by the adaptor)
// The solver reorders its arrays every step, so pointers are refreshed on every in-situ step; the
// arrays the adaptor owns (zeros, device, connectivity) are only rewritten when they must grow,
// so the adaptor's cost per step does not depend on the particle count.
#include <vtkNew.h>
#include <vtkSmartPointer.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "sim/insitu.hpp"

class vtkMultiBlockDataSet;
class vtkPolyData;

namespace spate::catalyst {

class ParticleDataset {
 public:
  ParticleDataset();
  ~ParticleDataset();
  ParticleDataset(const ParticleDataset&) = delete;
  ParticleDataset& operator=(const ParticleDataset&) = delete;

  // Points the dataset at the slabs' current buffers. `wanted(name)` says which point arrays to
  // attach (all when empty). The memory must stay valid until the pipelines have run.
  vtkMultiBlockDataSet* update(const std::vector<SlabView>& slabs, const std::function<bool(std::string_view)>& wanted = {});
  vtkMultiBlockDataSet* data() const;
  // A one-value double array in the dataset's field data.
  void set_constant(const std::string& name, double value);

 private:
  struct Partition;
  Partition& partition(int slab);

  vtkSmartPointer<vtkMultiBlockDataSet> blocks_;
  std::vector<std::unique_ptr<Partition>> partitions_;  // by global slab index, created on first use
};

}  // namespace spate::catalyst
