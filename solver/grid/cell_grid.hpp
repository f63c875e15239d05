#pragma once
// The local cell grid of one slab: the owned cell block (x columns [owned_lo, owned_hi), every y
// and z cell) plus one ghost layer around it (x halo columns, periodic image cells). Owned cells are
// numbered first, x slowest then y then z, so owned particles are contiguous after the sort and
// z-consecutive cells are contiguous in memory; ghost cells follow, in the same order.
//
// Particles are sorted by (cell, id) (SlabTopology over the backend's SlabArrays, which hand this
// grid the cell table): a pure function of the particle state, so the neighbour
// order, and therefore every floating-point sum, is the same however the domain is split.
#include <cstdint>
#include <span>
#include <vector>

#include "../particles/particle_store.hpp"
#include "cell_grid_view.hpp"
#include "lattice.hpp"

namespace spate {

class CellGrid {
 public:
  static constexpr std::uint32_t kOutside = 0xffffffffu;

  // x columns [owned_lo, owned_hi) are owned; ghosts may sit one cell beyond every face that has a
  // neighbour or a periodic image.
  void configure(const Lattice& lattice, int owned_lo, int owned_hi);

  const Lattice& lattice() const { return lattice_; }
  int owned_lo() const { return owned_lo_; }
  int owned_hi() const { return owned_hi_; }
  std::uint32_t cell_count() const { return owned_cells_ + ghost_cells_; }
  std::uint32_t owned_cell_count() const { return owned_cells_; }

  // Local index of global cell (ix, iy, iz), or kOutside if it is not in this grid.
  std::uint32_t local_cell(int ix, int iy, int iz) const;
  std::uint32_t local_cell_of(const float* const pos[3], std::size_t i) const;
  bool owns_column(int ix) const { return ix >= owned_lo_ && ix < owned_hi_; }

  // Particles of local cell c are [begin(c), end(c)).
  std::uint32_t begin(std::uint32_t c) const { return start_[c]; }
  std::uint32_t end(std::uint32_t c) const { return start_[c + 1]; }
  const std::vector<std::uint32_t>& starts() const { return start_; }
  // Takes the table from the arrays that sorted the particles (SlabArrays::build_table): `table`
  // was computed for a grid whose view was `built_for`, and its first cell_count() + 1 entries
  // become this grid's. A table of another geometry (a grid reconfigured since, e.g. by a
  // balancing pass) would number cells differently or end early: std::logic_error.
  void assign_starts(const CellGridView& built_for, std::span<const std::uint32_t> table);
  // The check of assign_starts alone, for a caller that wants it before it fetches the table.
  void require_geometry(const CellGridView& built_for, std::size_t entries) const;

  // The global cell coordinates of local cell c.
  void global_coords(std::uint32_t c, int out[3]) const;

  const CellGridView& view() const { return view_; }

  std::size_t bytes() const { return start_.capacity() * sizeof(std::uint32_t); }

 private:
  Lattice lattice_;
  int owned_lo_ = 0, owned_hi_ = 0;
  int lo_[3] = {0, 0, 0}, hi_[3] = {0, 0, 0};  // full local box including ghost layers
  int box_[3] = {0, 0, 0};
  std::uint32_t owned_cells_ = 0, ghost_cells_ = 0;
  std::vector<std::uint32_t> start_;  // cell_count + 1 prefix offsets
  CellGridView view_{};
};

}  // namespace spate
