#pragma once
// The global cell lattice: cell size >= kernel support, origin at the domain's lower corner. Every
// slab, ghost and probe uses these same integer cells, so ownership never depends on rounding that
// differs between devices.
#include <array>
#include <cmath>
#include <cstdint>

#include "../physics/host_device.hpp"

namespace spate {

struct Lattice {
  int dim = 3;
  float origin[3] = {0, 0, 0};
  // Per axis: at least one kernel support; stretched on periodic axes so the period is whole cells.
  float cell_size[3] = {1, 1, 1};
  float inv_cell[3] = {1, 1, 1};
  int cells[3] = {1, 1, 1};        // global cell counts
  bool periodic[3] = {false, false, false};
  float period[3] = {0, 0, 0};      // domain length along periodic axes (= cells * cell_size)

  SPATE_HD int cell_of(float x, int axis) const {
    return static_cast<int>(floorf((x - origin[axis]) * inv_cell[axis]));
  }
  SPATE_HD float upper(int axis) const { return origin[axis] + static_cast<float>(cells[axis]) * cell_size[axis]; }
};

// The coordinate of a periodic copy (a halo ghost across the periodic x boundary, or an image along
// a periodic y/z axis): x + offset, offset = +period for a copy of the first cell layer (it lands in
// the ghost layer above the last cell, global cell `cells`) and -period for a copy of the last
// layer (ghost cell -1). The float sum rounds to nearest, so a particle within an ulp of a cell
// face can land on the next face, one cell beyond the ghost layer, where the slab's grid has no
// cell (SlabTopology: "ghost outside the local grid"; the CPU path misfiled it). The copy is moved
// back by whole ulps into its layer (a few 1e-7 of the coordinate). Every backend computes copies
// with this one function, so results stay bit-identical; a non-finite x is returned shifted as is.
SPATE_HD float periodic_copy(const Lattice& L, int axis, float x, float offset) {
  const int target = offset > 0.0f ? L.cells[axis] : -1;
  const float y = x + offset;
  if (!(y - y == 0.0f)) return y;  // NaN or infinite: the position check reports it
  const int cell = L.cell_of(y, axis);
  if (cell == target) return y;
  // From the face of the target cell on the side the sum overshot, step inwards by ulps of the
  // copy's own magnitude until the lattice puts it in the target cell.
  const float inward = cell > target ? -INFINITY : INFINITY;
  float z = L.origin[axis] + static_cast<float>(cell > target ? target + 1 : target) * L.cell_size[axis];
  for (int k = 0; k < 64 && L.cell_of(z, axis) != target; ++k) z = nextafterf(z, inward);
  return z;
}

// A periodic shift applied to the copies of a pack, a stage or an image list.
struct Shift {
  int axis = -1;        // no shift
  float offset = 0.0f;  // +-period along axis
  Lattice lattice{};    // for periodic_copy()
  SPATE_HD float apply(float x) const { return periodic_copy(lattice, axis, x, offset); }
};

// The shift that copies the first (to_upper) or last cell layer along a periodic axis across the
// boundary.
inline Shift periodic_shift(const Lattice& L, int axis, bool to_upper) {
  return Shift{axis, to_upper ? L.period[axis] : -L.period[axis], L};
}

}  // namespace spate
