#pragma once
// The host plan of a slab's topology, computed from small metadata (the cell table's column
// offsets, emigrant and ghost counts) and shared by every backend: which x column migrates which
// way, the sort key of a particle, which contiguous owned ranges a halo sends, and which owned
// particles need no ghost at all (the interior that runs while the halo travels). Pure functions,
// tested on the CPU (tests/unit/test_slab_plan.cpp); particle_key is SPATE_HD so that the device
// computes exactly the keys the host would.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "../grid/cell_grid_view.hpp"
#include "../grid/lattice.hpp"
#include "../particles/particle_pack.hpp"
#include "../physics/host_device.hpp"

namespace spate {

class CellGrid;

// Sort keys: local cells [0, cells), then three bins past the cells. After the owned sort by
// (key, id) the particles leaving to the left, those leaving to the right and those outside the
// local grid (a bug in ownership) are each one contiguous range at the end.
struct KeyBins {
  static constexpr std::uint32_t kEmigrantLeft = 0, kEmigrantRight = 1, kLost = 2, kExtra = 3;
  std::uint32_t cells = 0;
  SPATE_HD std::uint32_t emigrant_left() const { return cells + kEmigrantLeft; }
  SPATE_HD std::uint32_t emigrant_right() const { return cells + kEmigrantRight; }
  SPATE_HD std::uint32_t lost() const { return cells + kLost; }
  SPATE_HD std::uint32_t count() const { return cells + kExtra; }  // key values
  // The cell table of a slab: the first particle of every key bin and the end. Its first
  // cells + 1 entries are a CellGrid's table for a grid of `cells` cells.
  SPATE_HD std::uint32_t table_entries() const { return count() + 1; }
};

// Ids must be below the run's id bound (SlabArrays::set_id_bound): the device sort orders
// (key, id) as one word, key << id_bits | id, with id_bits just wide enough for the bound, so a
// larger id would spill into the key bits and corrupt the order. Throws std::invalid_argument
// naming the first id that is not below `bound` (throw_id_not_below).
void require_ids_below(std::span<const std::uint32_t> ids, std::uint32_t bound);
[[noreturn]] void throw_id_not_below(std::uint32_t id, std::uint32_t bound);

// The key of a particle at (x, y, z): its local cell, or, for owned particles (`hops` not null),
// the emigrant bin of the direction its column migrates (hops[column]: -1 left, 0 here, +1 right).
SPATE_HD std::uint32_t particle_key(const CellGridView& g, const Lattice& L, const std::int8_t* hops, float x, float y,
                                    float z) {
  const KeyBins bins{g.cell_count()};
  const int cx = L.cell_of(x, 0);
  const int cy = L.dim >= 2 ? L.cell_of(y, 1) : 0;
  const int cz = L.dim >= 3 ? L.cell_of(z, 2) : 0;
  if (hops != nullptr && cx >= 0 && cx < L.cells[0]) {
    if (hops[cx] < 0) return bins.emigrant_left();
    if (hops[cx] > 0) return bins.emigrant_right();
  }
  const std::uint32_t cell = g.local_cell(cx, cy, cz);
  return cell == CellGridView::kOutside ? bins.lost() : cell;
}

// Per global x column, the neighbour hop an owned particle in it takes (-1, 0, +1): towards the
// owner, and with periodic x the shorter way round (ties to the left). The rule of migrate().
std::vector<std::int8_t> migration_hops(const std::vector<int>& faces, int slab, bool periodic_x);

struct ParticleRange {
  std::size_t first = 0, count = 0;
  std::size_t end() const { return first + count; }
  bool operator==(const ParticleRange&) const = default;
};

enum Side : int { kLeft = 0, kRight = 1 };

// What a slab sends its neighbours as ghosts: the owned particles of its first x column to the
// left, of its last to the right (each one contiguous range after the owned sort, x being the
// slowest cell axis), with the period added when the copy wraps across a periodic x boundary.
// `column_starts` are the first particles of the owned columns, plus the owned count at the end.
struct HaloSends {
  std::array<ParticleRange, 2> range;
  std::array<Shift, 2> shift;
};
HaloSends plan_halo_sends(const CellGrid& grid, std::span<const std::uint32_t> column_starts, bool has_left, bool has_right);

// Owned particles split for the overlap of the halo with the fluid loop: interior ones (every
// column but the first if there is a left neighbour and the last if there is a right one) see
// owned particles and images of owned particles only, which are ready before the halo arrives;
// the boundary ranges before and after need the halo (empty on a side without a neighbour, so that
// a lone slab computes its rates in one pass).
struct OwnedSplit {
  ParticleRange before, interior, after;
};
OwnedSplit plan_owned_split(const CellGrid& grid, std::span<const std::uint32_t> column_starts, bool has_left, bool has_right);

// Table entries to read back for the column starts: first, stride (cells per x column), count.
struct TableRead {
  std::uint32_t first = 0, stride = 1, count = 0;
};
TableRead column_starts_read(const CellGrid& grid);

}  // namespace spate
