#include "slab_plan.hpp"

#include <stdexcept>
#include <string>

#include "../grid/cell_grid.hpp"
#include "slab_layout.hpp"

namespace spate {

std::vector<std::int8_t> migration_hops(const std::vector<int>& faces, int slab, bool periodic_x) {
  const SlabLayout layout{faces};
  const int S = layout.slabs();
  std::vector<std::int8_t> hops(static_cast<std::size_t>(faces.back()), 0);
  for (int column = 0; column < faces.back(); ++column) {
    const int owner = layout.owner_of(column);
    if (owner == slab) continue;
    bool left = owner < slab;
    if (periodic_x) {
      const int dl = (slab - owner + S) % S, dr = (owner - slab + S) % S;
      left = dl <= dr;
    }
    hops[column] = left ? -1 : 1;
  }
  return hops;
}

void throw_id_not_below(std::uint32_t id, std::uint32_t bound) {
  throw std::invalid_argument("particle id " + std::to_string(id) + " is not below the run's id bound " + std::to_string(bound) +
                              " (the largest id + 1, for which the sort words were sized)");
}

void require_ids_below(std::span<const std::uint32_t> ids, std::uint32_t bound) {
  for (const std::uint32_t id : ids)
    if (id >= bound) throw_id_not_below(id, bound);
}

TableRead column_starts_read(const CellGrid& grid) {
  const Lattice& L = grid.lattice();
  const std::uint32_t per_column = static_cast<std::uint32_t>((L.dim >= 2 ? L.cells[1] : 1) * (L.dim >= 3 ? L.cells[2] : 1));
  return {0, per_column, static_cast<std::uint32_t>(grid.owned_hi() - grid.owned_lo() + 1)};
}

namespace {
void check_starts(const CellGrid& grid, std::span<const std::uint32_t> starts) {
  if (starts.size() != static_cast<std::size_t>(grid.owned_hi() - grid.owned_lo() + 1))
    throw std::logic_error("slab plan: one column start per owned column plus the end expected");
}
ParticleRange between(std::uint32_t b, std::uint32_t e) { return {b, e - b}; }
}  // namespace

HaloSends plan_halo_sends(const CellGrid& grid, std::span<const std::uint32_t> starts, bool has_left, bool has_right) {
  check_starts(grid, starts);
  const Lattice& L = grid.lattice();
  const std::size_t n = starts.size() - 1;
  HaloSends h;
  if (has_left) h.range[kLeft] = between(starts[0], starts[1]);
  if (has_right) h.range[kRight] = between(starts[n - 1], starts[n]);
  // Wrapping across the periodic x boundary shifts the copy by the period, computed by the owner
  // so that every split produces the same float.
  if (has_left && grid.owned_lo() == 0) h.shift[kLeft] = periodic_shift(L, 0, true);
  if (has_right && grid.owned_hi() == L.cells[0]) h.shift[kRight] = periodic_shift(L, 0, false);
  return h;
}

OwnedSplit plan_owned_split(const CellGrid& grid, std::span<const std::uint32_t> starts, bool has_left, bool has_right) {
  check_starts(grid, starts);
  const std::size_t n = starts.size() - 1;
  OwnedSplit s;
  const std::size_t first = has_left ? 1 : 0, last = n - (has_right ? 1 : 0);
  if (n < first + (has_right ? 1 : 0) + 1) {  // no column is free of both faces with a neighbour
    s.before = between(0, starts[n]);
    s.interior = s.after = {starts[n], 0};
    return s;
  }
  s.before = between(starts[0], starts[first]);
  s.interior = between(starts[first], starts[last]);
  s.after = between(starts[last], starts[n]);
  return s;
}

}  // namespace spate
