#pragma once
// Plain-data view of a slab's cell grid for the pair loops of both backends: maps global cell
// coordinates to local cells and yields each neighbour cell row as one contiguous particle range.
#include <cstdint>

#include "../physics/host_device.hpp"

namespace spate {

struct CellGridView {
  static constexpr std::uint32_t kOutside = 0xffffffffu;
  int dim;
  int cells[3];             // global cell counts (1 for unused axes)
  int owned_lo, owned_hi;   // owned x columns
  int lo[3], box[3];        // the whole local box with ghost layers
  std::uint32_t owned_cells;
  const std::uint32_t* start;  // prefix offsets, cell_count + 1

  SPATE_HD std::uint32_t cell_count() const { return owned_cells + static_cast<std::uint32_t>(box[0] * box[1] * box[2]); }

  SPATE_HD std::uint32_t local_cell(int ix, int iy, int iz) const {
    if (ix >= owned_lo && ix < owned_hi && iy >= 0 && iy < cells[1] && iz >= 0 && iz < cells[2])
      return static_cast<std::uint32_t>(((ix - owned_lo) * cells[1] + iy) * cells[2] + iz);
    const int gx = ix - lo[0], gy = iy - lo[1], gz = iz - lo[2];
    if (gx < 0 || gx >= box[0] || gy < 0 || gy >= box[1] || gz < 0 || gz >= box[2]) return kOutside;
    return owned_cells + static_cast<std::uint32_t>((gx * box[1] + gy) * box[2] + gz);
  }

  // Calls body(begin, end) for the particles of every cell within one cell of owned cell `c`
  // (global coordinates g), in a fixed order: rows by x then y, each row along the last axis.
  template <class Body>
  SPATE_HD void for_each_neighbour_range(const int g[3], Body&& body) const {
    const int last = dim - 1;  // rows run along the last axis, whose cells are adjacent in memory
    const int ny_lo = dim == 3 ? -1 : 0, ny_hi = dim == 3 ? 1 : 0;
    for (int dx = -1; dx <= 1; ++dx) {
      for (int dy = ny_lo; dy <= ny_hi; ++dy) {
        std::uint32_t row[3];
        for (int k = 0; k < 3; ++k) {
          int c[3] = {g[0] + dx, g[1], g[2]};
          if (dim == 3) c[1] += dy;
          c[last] += k - 1;
          row[k] = local_cell(c[0], c[1], c[2]);
        }
        if (row[0] != kOutside && row[1] == row[0] + 1 && row[2] == row[1] + 1) {
          body(start[row[0]], start[row[2] + 1]);
        } else {
          for (int k = 0; k < 3; ++k)
            if (row[k] != kOutside) body(start[row[k]], start[row[k] + 1]);
        }
      }
    }
  }
};

// Whether two views number the same cells the same way (their tables are interchangeable).
inline bool same_geometry(const CellGridView& a, const CellGridView& b) {
  if (a.dim != b.dim || a.owned_lo != b.owned_lo || a.owned_hi != b.owned_hi || a.owned_cells != b.owned_cells) return false;
  for (int k = 0; k < 3; ++k)
    if (a.cells[k] != b.cells[k] || a.lo[k] != b.lo[k] || a.box[k] != b.box[k]) return false;
  return true;
}

}  // namespace spate
