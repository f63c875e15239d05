#pragma once
// SlabArrays in host memory: the CPU backend's particles (cpu::Kernels runs SlabTopology on them,
// the same orchestration as a GPU step) and the reference implementation of the primitives; the
// CUDA backend implements the same primitives with CUB and a few kernels
// (backend/cuda/cuda_kernels.cu).
#include <array>
#include <vector>

#include "slab_arrays.hpp"

namespace spate {

class HostSlabArrays : public SlabArrays {
 public:
  // Particles in a store of its own (a stand-in device: the worker's host store is then a mirror).
  explicit HostSlabArrays(int dim) : own_(dim), store_(&own_), grid_(&own_grid_) {}
  // Particles in `store` and their cell table in `grid`: the worker's host store and grid (the CPU
  // backend), so upload and download copy nothing, outputs and in situ read the arrays the loops
  // write (zero copy), and the loops may take the worker's store and grid as they are.
  HostSlabArrays(ParticleStore& store, CellGrid& grid) : store_(&store), grid_(&grid) {}
  HostSlabArrays(const HostSlabArrays&) = delete;
  HostSlabArrays& operator=(const HostSlabArrays&) = delete;

  std::size_t size() const override { return store_->size(); }
  std::size_t owned() const override { return store_->owned(); }
  void upload(const ParticleStore& host) override;
  void download(ParticleStore& host, CellGrid& grid) override;
  void truncate(std::size_t n) override;
  void set_owned(std::size_t n) override { store_->set_owned(n); }
  void set_id_bound(std::uint32_t bound) override;
  void set_migration_hops(const std::vector<std::int8_t>& hops) override { hops_ = hops; }
  void compute_keys(const CellGrid& geometry, std::size_t first, std::size_t last, bool migrating) override;
  void sort_by_key(std::size_t first, std::size_t last) override;
  void build_table(const CellGrid& geometry) override;
  std::vector<std::uint32_t> table_entries(const TableRead& read) override;
  void stage(Side side, FieldSet set, ParticleRange range, Shift shift) override;
  std::array<std::size_t, 2> exchange(SlabTransport& t, FieldSet set) override;
  void append_received(Side side, FieldSet set) override;
  void scatter_received(Side side) override;
  void forget_images() override;
  void make_images(const CellGrid& geometry, int axis) override;
  void record_halo_slots(std::size_t left, std::size_t right) override;
  void refresh_images(ImagePart part) override;
  std::vector<std::uint32_t> remove_escaped(const OpenSides& open) override;
  std::uint32_t wrap_and_find_position_fault(const Lattice& L) override;
  std::uint32_t find_unhealthy(const HealthLimits& limits) override;

  // The particles and the cell grid the physics loops of a host backend run on.
  ParticleStore& store() { return *store_; }
  const CellGrid& grid() const { return *grid_; }
  const std::vector<std::uint32_t>& halo_slots(Side side) const { return slots_[side]; }
  const std::vector<std::uint32_t>& image_targets(int axis, ImagePart part) const {
    return images_[axis][static_cast<int>(part)].target;
  }

 private:
  ParticleStore own_;
  ParticleStore* store_;               // own_ or the shared store
  CellGrid own_grid_;
  CellGrid* grid_;                     // geometry of the last build_table, with its cell table
  std::vector<std::uint32_t> keys_;    // one per particle
  std::vector<std::uint32_t> table_;   // KeyBins::table_entries() starts, for the geometry of grid_
  std::uint32_t id_bound_ = kNoFault;
  std::vector<std::uint32_t> perm_;    // of the last sort: new slot k held old first + perm_[k]
  std::vector<std::uint32_t> counts_;  // the counting sort's bins
  std::size_t perm_first_ = 0;
  std::vector<std::int8_t> hops_;
  std::array<Bytes, 2> outbox_, inbox_;
  std::array<std::vector<std::uint32_t>, 2> slots_;
  // Periodic images per axis and part: source and target slots, in creation order.
  struct Images {
    std::vector<std::uint32_t> source, target;
  };
  std::array<std::array<Images, 2>, 3> images_;
};

}  // namespace spate
