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
#include <vtkSignedCharArray.h>
#include <vtkTypeInt32Array.h>
#include <vtkUnsignedCharArray.h>
#include <vtkUnsignedIntArray.h>

#include <algorithm>
#include <map>
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
    device->SetName("device");
    phase->SetName("phase");
    points->SetData(xyz);
    poly->SetPoints(points);
  }

  // The VTK array wrapping one exported solver field, made on first use.
  vtkDataArray* array_for(const SlabArray& a) {
    auto& slot = arrays[std::string(a.name)];
    if (!slot) {
      if (a.components > 1) slot = vtkSmartPointer<vtkSOADataArrayTemplate<float>>::New();
      else if (a.type == FieldType::F32) slot = vtkSmartPointer<vtkFloatArray>::New();
      else if (a.type == FieldType::U32) slot = vtkSmartPointer<vtkUnsignedIntArray>::New();
      else slot = vtkSmartPointer<vtkUnsignedCharArray>::New();
      slot->SetNumberOfComponents(a.components);
      slot->SetName(std::string(a.name).c_str());
    }
    return slot;
  }

  void wrap(const SlabView& v, const std::function<bool(std::string_view)>& wanted) {
    const auto n = static_cast<vtkIdType>(v.owned);
    const float* zero = reserve_filled(zeros, v.owned, [](auto& b) { std::fill(b.begin(), b.end(), 0.0f); });
    auto component = [&](const void* p) { return unconst(static_cast<const float*>(p && n > 0 ? p : zero)); };
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
    for (const SlabArray& a : v.arrays) {
      vtkDataArray* array = array_for(a);
      attach(array, a.name, [&] {
        if (auto* soa = vtkSOADataArrayTemplate<float>::SafeDownCast(array)) {
          for (int k = 0; k < a.components; ++k) soa->SetArray(k, component(a.data[k]), n, true, true);
        } else if (auto* f = vtkFloatArray::SafeDownCast(array)) {
          f->SetArray(component(a.data[0]), n, 1);
        } else if (auto* u = vtkUnsignedIntArray::SafeDownCast(array)) {
          u->SetArray(unconst(static_cast<const unsigned int*>(a.data[0] && n > 0 ? a.data[0] : zero)), n, 1);
        } else if (auto* c = vtkUnsignedCharArray::SafeDownCast(array)) {
          c->SetArray(unconst(static_cast<const unsigned char*>(a.data[0] && n > 0 ? a.data[0] : zero)), n, 1);
        }
      });
    }
    attach(device, "device", [&] {
      const int owner = v.slab;
      device->SetArray(reserve_filled(device_ids, v.owned, [owner](auto& b) { std::fill(b.begin(), b.end(), owner); }), n, 1);
    });
    // Several fluids: the phase of each particle, derived from its material (one byte a particle,
    // refilled every call: particles are re-sorted every step).
    if (v.fluids > 1) {
      const SlabArray* kind = v.array("kind");
      attach(phase, "phase", [&] {
        phase_ids.resize(std::max<std::size_t>(v.owned, 1));
        const auto* m = kind ? kind->values<std::uint8_t>() : nullptr;
        for (std::size_t i = 0; i < v.owned; ++i) phase_ids[i] = m ? phase_of(m[i], v.fluids) : std::int8_t{-1};
        phase->SetArray(phase_ids.data(), n, 1);
      });
    }

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
  std::map<std::string, vtkSmartPointer<vtkDataArray>> arrays;  // by exported name
  vtkNew<vtkIntArray> device;
  vtkNew<vtkSignedCharArray> phase;
  vtkNew<vtkTypeInt32Array> offsets;
  vtkNew<vtkTypeInt32Array> connectivity;
  vtkNew<vtkCellArray> verts;
  std::vector<float> zeros;
  std::vector<int> device_ids;
  std::vector<signed char> phase_ids;
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
