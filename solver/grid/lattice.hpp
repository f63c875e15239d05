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

}  // namespace spate
