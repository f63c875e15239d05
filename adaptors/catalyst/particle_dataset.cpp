#include "particle_dataset.hpp"

#include <vtkCellArray.h>
#include <vtkCompositeDataSet.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkFloatArray.h>
#include <vtkInformation.h>
#include <vtkIntArray.h>
#include <vtkMultiBlockDataSet.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSOADataArrayTemplate.h>
#include <vtkTypeInt32Array.h>
#include <vtkUnsignedCharArray.h>
#include <vtkUnsignedIntArray.h>

#include <algorithm>
#include <numeric>
#include <string>

namespace spate::catalyst {

namespace {

// Grows an adaptor-owned buffer to at least n (+50 % headroom) and refills it; the contents only
// depend on the index, so a buffer that is big enough is reused as it is.
template <class T, class Fill>
T* reserve_filled(std::vector<T>& buffer, std::size_t n, Fill fill) {
  n = std::max<std::size_t>(n, 1);  // never hand VTK a null pointer
  if (buffer.size() < n) {
    buffer.resize(std::max(n, buffer.size() + buffer.size() / 2));
    fill(buffer);
  }
  return buffer.data();
}

// VTK's SetArray takes non-const pointers; with save = 1 it neither frees nor writes them.
template <class T>
T* unconst(const T* p) {
  return const_cast<T*>(p);
}

}  // namespace

struct ParticleDataset::Partition {
  Partition() {
    xyz->SetNumberOfComponents(3);
    xyz->SetName("Points");
    velocity->SetNumberOfComponents(3);
    velocity->SetName("velocity");
    pressure->SetName("pressure");
    density->SetName("density");
    id->SetName("id");
    kind->SetName("kind");
    device->SetName("device");
    points->SetData(xyz);
    poly->SetPoints(points);
  }

  void wrap(const SlabView& v, const std::function<bool(std::string_view)>& wanted) {
    const auto n = static_cast<vtkIdType>(v.owned);
    const float* zero = reserve_filled(zeros, v.owned, [](auto& b) { std::fill(b.begin(), b.end(), 0.0f); });
    auto component = [&](const float* p) { return unconst(p && n > 0 ? p : zero); };
    for (int k = 0; k < 3; ++k) xyz->SetArray(k, component(v.pos[k]), n, /*updateMaxId=*/true, /*save=*/true);
    points->Modified();

    vtkPointData* pd = poly->GetPointData();
    auto attach = [&](vtkDataArray* array, std::string_view name, auto&& set) {
      if (wanted && !wanted(name)) {
        pd->RemoveArray(std::string(name).c_str());
        return;
      }
      set();
      if (!pd->HasArray(std::string(name).c_str())) pd->AddArray(array);
    };
    attach(velocity, "velocity", [&] {
      for (int k = 0; k < 3; ++k) velocity->SetArray(k, component(v.vel[k]), n, true, true);
    });
    attach(pressure, "pressure", [&] { pressure->SetArray(component(v.pressure), n, 1); });
    attach(density, "density", [&] { density->SetArray(component(v.density), n, 1); });
    attach(id, "id", [&] {
      const std::uint32_t* p = v.id && n > 0 ? v.id : reinterpret_cast<const std::uint32_t*>(zero);
      id->SetArray(unconst(p), n, 1);
    });
    attach(kind, "kind", [&] {
      const std::uint8_t* p = v.kind && n > 0 ? v.kind : reinterpret_cast<const std::uint8_t*>(zero);
      kind->SetArray(unconst(p), n, 1);
    });
    attach(device, "device", [&] {
      const int owner = v.slab;
      device->SetArray(reserve_filled(device_ids, v.owned, [owner](auto& b) { std::fill(b.begin(), b.end(), owner); }), n, 1);
    });

    // One vertex cell per particle, so that every representation (not only Point Gaussian) and
    // every writer sees the particles. Offsets 0..n and connectivity 0..n-1 depend only on n.
    offsets->SetArray(reserve_filled(offset_ids, v.owned + 1, [](auto& b) { std::iota(b.begin(), b.end(), 0); }), n + 1, 1);
    connectivity->SetArray(reserve_filled(connectivity_ids, v.owned, [](auto& b) { std::iota(b.begin(), b.end(), 0); }), n, 1);
    verts->SetData(offsets, connectivity);
    poly->SetVerts(verts);
    poly->Modified();
  }

  vtkNew<vtkPolyData> poly;
  vtkNew<vtkPoints> points;
  vtkNew<vtkSOADataArrayTemplate<float>> xyz;
  vtkNew<vtkSOADataArrayTemplate<float>> velocity;
  vtkNew<vtkFloatArray> pressure;
  vtkNew<vtkFloatArray> density;
  vtkNew<vtkUnsignedIntArray> id;
  vtkNew<vtkUnsignedCharArray> kind;
  vtkNew<vtkIntArray> device;
  vtkNew<vtkTypeInt32Array> offsets;
  vtkNew<vtkTypeInt32Array> connectivity;
  vtkNew<vtkCellArray> verts;
  std::vector<float> zeros;
  std::vector<int> device_ids;
  std::vector<vtkTypeInt32> offset_ids;
  std::vector<vtkTypeInt32> connectivity_ids;
};

ParticleDataset::ParticleDataset() : blocks_(vtkSmartPointer<vtkMultiBlockDataSet>::New()) {}

ParticleDataset::~ParticleDataset() = default;

ParticleDataset::Partition& ParticleDataset::partition(int slab) {
  if (static_cast<std::size_t>(slab) >= partitions_.size()) partitions_.resize(slab + 1);
  if (!partitions_[slab]) partitions_[slab] = std::make_unique<Partition>();
  return *partitions_[slab];
}

vtkMultiBlockDataSet* ParticleDataset::update(const std::vector<SlabView>& slabs, const std::function<bool(std::string_view)>& wanted) {
  const int count = slabs.empty() ? 0 : slabs.front().slab_count;
  if (static_cast<int>(blocks_->GetNumberOfBlocks()) != count) {
    blocks_->SetNumberOfBlocks(count);
    for (int k = 0; k < count; ++k) blocks_->GetMetaData(k)->Set(vtkCompositeDataSet::NAME(), ("slab_" + std::to_string(k)).c_str());
  }
  for (const SlabView& v : slabs) {
    Partition& p = partition(v.slab);
    p.wrap(v, wanted);
    if (blocks_->GetBlock(v.slab) != p.poly.GetPointer()) blocks_->SetBlock(v.slab, p.poly);
  }
  blocks_->Modified();
  return blocks_;
}

vtkMultiBlockDataSet* ParticleDataset::data() const { return blocks_; }

void ParticleDataset::set_constant(const std::string& name, double value) {
  vtkNew<vtkDoubleArray> a;
  a->SetName(name.c_str());
  a->SetNumberOfTuples(1);
  a->SetValue(0, value);
  blocks_->GetFieldData()->AddArray(a);
}

}  // namespace spate::catalyst
