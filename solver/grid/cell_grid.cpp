#include "cell_grid.hpp"

#include <algorithm>
#include <numeric>
#include <stdexcept>
#include <string>

namespace spate {

void CellGrid::configure(const Lattice& lattice, int owned_lo, int owned_hi) {
  lattice_ = lattice;
  owned_lo_ = owned_lo;
  owned_hi_ = owned_hi;
  const int d = lattice.dim;
  for (int a = 0; a < 3; ++a) {
    if (a >= d) {
      lo_[a] = 0;
      hi_[a] = 1;
      continue;
    }
    const int l = a == 0 ? owned_lo : 0;
    const int h = a == 0 ? owned_hi : lattice.cells[a];
    // One ghost layer on every side: x halos always (a neighbour or a periodic image may be
    // there), y/z layers exist only where periodic images are made.
    const bool layer = a == 0 || lattice.periodic[a];
    lo_[a] = layer ? l - 1 : l;
    hi_[a] = layer ? h + 1 : h;
  }
  for (int a = 0; a < 3; ++a) box_[a] = hi_[a] - lo_[a];
  const int ny = d >= 2 ? lattice.cells[1] : 1;
  const int nz = d >= 3 ? lattice.cells[2] : 1;
  owned_cells_ = static_cast<std::uint32_t>((owned_hi - owned_lo) * ny * nz);
  ghost_cells_ = static_cast<std::uint32_t>(box_[0] * box_[1] * box_[2]);
  start_.assign(cell_count() + 1, 0);
  view_ = CellGridView{};
  view_.dim = d;
  for (int a = 0; a < 3; ++a) {
    view_.cells[a] = a < d ? lattice.cells[a] : 1;
    view_.lo[a] = lo_[a];
    view_.box[a] = box_[a];
  }
  view_.owned_lo = owned_lo;
  view_.owned_hi = owned_hi;
  view_.owned_cells = owned_cells_;
  view_.start = start_.data();
}

std::uint32_t CellGrid::local_cell(int ix, int iy, int iz) const { return view_.local_cell(ix, iy, iz); }

std::uint32_t CellGrid::local_cell_of(const float* const pos[3], std::size_t i) const {
  int c[3] = {0, 0, 0};
  for (int a = 0; a < lattice_.dim; ++a) c[a] = lattice_.cell_of(pos[a][i], a);
  return local_cell(c[0], c[1], c[2]);
}

void CellGrid::global_coords(std::uint32_t c, int out[3]) const {
  const int ny = lattice_.dim >= 2 ? lattice_.cells[1] : 1;
  const int nz = lattice_.dim >= 3 ? lattice_.cells[2] : 1;
  if (c < owned_cells_) {
    out[2] = static_cast<int>(c % nz);
    out[1] = static_cast<int>((c / nz) % ny);
    out[0] = static_cast<int>(c / (nz * ny)) + owned_lo_;
    return;
  }
  const std::uint32_t g = c - owned_cells_;
  out[2] = static_cast<int>(g % box_[2]) + lo_[2];
  out[1] = static_cast<int>((g / box_[2]) % box_[1]) + lo_[1];
  out[0] = static_cast<int>(g / (box_[2] * box_[1])) + lo_[0];
}

void CellGrid::assign_starts(const CellGridView& built_for, std::span<const std::uint32_t> table) {
  require_geometry(built_for, table.size());
  std::copy(table.begin(), table.begin() + static_cast<std::ptrdiff_t>(start_.size()), start_.begin());
}

void CellGrid::require_geometry(const CellGridView& built_for, std::size_t entries) const {
  if (!same_geometry(built_for, view_) || entries < start_.size())
    throw std::logic_error("CellGrid: a cell table of " + std::to_string(entries) + " entries built for a grid of " +
                           std::to_string(built_for.cell_count()) + " cells (owned columns " + std::to_string(built_for.owned_lo) + "-" +
                           std::to_string(built_for.owned_hi) + ") given to a grid of " + std::to_string(cell_count()) + " cells (owned columns " +
                           std::to_string(owned_lo_) + "-" + std::to_string(owned_hi_) + ")");
}

}  // namespace spate
