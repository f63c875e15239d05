#pragma once
// The data-movement primitives of a slab whose particles live in their own arrays (device memory
// for the CUDA backend; host memory for HostSlabArrays, the reference the CPU tests run). The
// topology of a step (migration, the (cell, id) sort, halos, refreshes: SlabTopology) is written
// once over these; an implementation only moves data and never decides what to move.
//
// Particles [0, owned) are this slab's, [owned, size) ghosts. Each particle has a sort key
// (slab_plan.hpp: particle_key) kept next to its fields; the cell table is computed from the keys.
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "../comm/transport.hpp"
#include "../grid/cell_grid.hpp"
#include "../particles/particle_pack.hpp"
#include "../particles/particle_store.hpp"
#include "particle_checks.hpp"
#include "slab_plan.hpp"

namespace spate {

enum class ImagePart : int { Local = 0, Halo = 1 };

class SlabArrays {
 public:
  static constexpr std::uint32_t kNoFault = 0xffffffffu;
  virtual ~SlabArrays() = default;

  virtual std::size_t size() const = 0;
  virtual std::size_t owned() const = 0;

  // Host copies. `upload`: every field of every host particle (take_share, restarts).
  // `download`: the host mirror for output steps: every field of the owned particles, the Ghost
  // fields of the ghosts, and the cell table of the last build_table into `grid`, which must
  // still have that table's geometry (CellGrid::assign_starts; probes interpolate over ghosts).
  virtual void upload(const ParticleStore& host) = 0;
  virtual void download(ParticleStore& host, CellGrid& grid) = 0;

  // Every id of the run is below `bound` (the largest id + 1 over all slabs; ids never change), so
  // a device sort may use a narrower (key, id) word. Ids are checked where they enter (upload,
  // and the particles already held when the bound changes): one that is not below the bound is
  // an error (require_ids_below), never ORed into the key bits. Default: no bound but the
  // reserved 0xffffffff (kNoFault).
  virtual void set_id_bound(std::uint32_t bound) = 0;
  // Keeps particles [0, n); the owned count becomes min(owned, n).
  virtual void truncate(std::size_t n) = 0;
  // Particles [0, n) are owned (after immigrants were appended).
  virtual void set_owned(std::size_t n) = 0;

  // Per global x column, the hop of migrating owned particles (migration_hops).
  virtual void set_migration_hops(const std::vector<std::int8_t>& hops) = 0;
  // Keys of particles [first, last): particle_key with the hops (owned particles) or without.
  virtual void compute_keys(const CellGrid& geometry, std::size_t first, std::size_t last, bool migrating) = 0;
  // Sorts [first, last) by (key, id); every field and the keys follow.
  virtual void sort_by_key(std::size_t first, std::size_t last) = 0;
  // The first particle of every key bin (KeyBins{geometry.cell_count()}.count() + 1 entries) from
  // the keys of all particles, which must be non-decreasing; the physics loops use its first
  // cell_count() + 1 entries.
  virtual void build_table(const CellGrid& geometry) = 0;
  // Host copies of table entries first, first + stride, ... (count of them).
  virtual std::vector<std::uint32_t> table_entries(const TableRead& read) = 0;

  // Neighbour payload. `stage` copies the fields of `set` of particles `range` into the outgoing
  // buffer of `side`, adding shift.offset to pos[shift.axis]; `exchange` delivers both outgoing
  // buffers to the neighbours and receives theirs (collective with both; returns the particle
  // counts received from left and right); the received particles are then appended (new
  // particles at the end; their fields outside `set` are zero) or scattered into the halo slots
  // recorded by record_halo_slots.
  virtual void stage(Side side, FieldSet set, ParticleRange range, Shift shift) = 0;
  virtual std::array<std::size_t, 2> exchange(SlabTransport& t, FieldSet set) = 0;
  virtual void append_received(Side side, FieldSet set) = 0;
  virtual void scatter_received(Side side) = 0;  // FieldSet::Refresh

  // Drops the record of the previous halo's images (a new halo is being built).
  virtual void forget_images() = 0;
  // Periodic images along `axis` of the particles there are now: every particle in the first cell
  // layer gets a copy one period up, every particle in the last layer one period down, appended
  // (its Ghost fields; the others are zero);
  // first the images of particles in owned x columns (ImagePart::Local), then those of particles
  // in the halo columns (ImagePart::Halo). The source of each image is remembered for
  // refresh_images. (The order of creation does not matter: the ghost sort follows.)
  virtual void make_images(const CellGrid& geometry, int axis) = 0;
  // After the ghost sort: where the halo ghosts received from the left ([owned, owned + left))
  // and the right (the next `right`) and every image now sit, using the permutation of the last
  // sort_by_key.
  virtual void record_halo_slots(std::size_t left, std::size_t right) = 0;
  // Copies the Refresh fields of the images of `part` from their sources, axis by axis. Local
  // images depend only on owned particles (an image keeps its source's x column), so they can be
  // refreshed before the halo arrives; halo images after it.
  virtual void refresh_images(ImagePart part) = 0;

  // Removes the owned fluid particles that left through an open side (escaped(), particle_checks.hpp)
  // and returns their ids in increasing order. The ghosts are dropped too (they are stale after
  // the predictor anyway); the order of the particles kept may change (the next sort restores it).
  virtual std::vector<std::uint32_t> remove_escaped(const OpenSides& open) = 0;

  // Device reductions with the host's predicates (particle_checks.hpp). Wraps the owned positions
  // on periodic axes and returns the lowest id whose position is faulty (kNoFault if none).
  virtual std::uint32_t wrap_and_find_position_fault(const Lattice& L) = 0;
  // The lowest id of an owned fluid particle that fails the health check, or kNoFault.
  virtual std::uint32_t find_unhealthy(const HealthLimits& limits) = 0;
};

}  // namespace spate
