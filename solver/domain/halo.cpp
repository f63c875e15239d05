#include "halo.hpp"

#include <numeric>

#include "slab_layout.hpp"
#include "slab_plan.hpp"

namespace spate {

namespace {
// Owned particles in x column `column` are contiguous after the owned sort (x is the slowest axis).
void column_range(const CellGrid& grid, int column, std::vector<std::uint32_t>& out) {
  out.clear();
  const Lattice& L = grid.lattice();
  const int ny = L.dim >= 2 ? L.cells[1] : 1;
  const int nz = L.dim >= 3 ? L.cells[2] : 1;
  const std::uint32_t first_cell = static_cast<std::uint32_t>((column - grid.owned_lo()) * ny * nz);
  const std::uint32_t b = grid.begin(first_cell), e = grid.begin(first_cell + ny * nz);
  out.resize(e - b);
  std::iota(out.begin(), out.end(), b);
}
}  // namespace

void Halo::build(ParticleStore& p, CellGrid& grid, SlabTransport& transport) {
  const Lattice& L = grid.lattice();
  const int s = transport.slab();
  const bool has_left = transport.left_of(s) >= 0, has_right = transport.right_of(s) >= 0;
  // Wrapping across the periodic x boundary shifts the copy by the period, computed by the owner
  // so that every split produces the same float.
  Shift to_left, to_right;
  if (has_left && grid.owned_lo() == 0) to_left = Shift{0, L.period[0]};
  if (has_right && grid.owned_hi() == L.cells[0]) to_right = Shift{0, -L.period[0]};
  column_range(grid, grid.owned_lo(), send_left_);
  column_range(grid, grid.owned_hi() - 1, send_right_);
  if (!has_left) send_left_.clear();
  if (!has_right) send_right_.clear();
  Bytes from_left, from_right;
  transport.exchange(pack_particles(p, send_left_, FieldSet::Ghost, to_left),
                     pack_particles(p, send_right_, FieldSet::Ghost, to_right), from_left, from_right);
  const std::size_t owned = p.owned();
  const std::size_t n_left = unpack_append(p, from_left, FieldSet::Ghost);
  const std::size_t n_right = unpack_append(p, from_right, FieldSet::Ghost);

  image_source_.clear();
  image_target_.clear();
  for (int axis = 1; axis < L.dim; ++axis)
    if (L.periodic[axis]) make_periodic_images(p, grid, axis);

  grid.sort_ghosts(p);
  // Translate pre-sort ghost positions into their slots after the sort.
  const auto& perm = grid.ghost_permutation();
  std::vector<std::uint32_t> slot_of(perm.size());
  for (std::size_t k = 0; k < perm.size(); ++k) slot_of[perm[k]] = static_cast<std::uint32_t>(owned + k);
  auto slot = [&](std::size_t absolute) { return absolute < owned ? static_cast<std::uint32_t>(absolute) : slot_of[absolute - owned]; };
  slots_left_.resize(n_left);
  slots_right_.resize(n_right);
  for (std::size_t k = 0; k < n_left; ++k) slots_left_[k] = slot(owned + k);
  for (std::size_t k = 0; k < n_right; ++k) slots_right_[k] = slot(owned + n_left + k);
  for (auto& src : image_source_) src = slot(src);
  for (auto& dst : image_target_) dst = slot(dst);
  ghosts_ = p.ghosts();
}

// Every particle (owned or ghost) in the first/last layer along `axis` gets an image one period
// away, so particles near that boundary see their periodic neighbours.
void Halo::make_periodic_images(ParticleStore& p, const CellGrid& grid, int axis) {
  const Lattice& L = grid.lattice();
  const std::size_t n = p.size();
  std::vector<std::uint32_t> low, high;
  for (std::size_t i = 0; i < n; ++i) {
    const int c = L.cell_of(p.pos[axis][i], axis);
    if (c == 0) low.push_back(static_cast<std::uint32_t>(i));
    if (c == L.cells[axis] - 1) high.push_back(static_cast<std::uint32_t>(i));
  }
  for (auto* list : {&low, &high}) {
    const float offset = list == &low ? L.period[axis] : -L.period[axis];
    const std::size_t first = p.size();
    unpack_append(p, pack_particles(p, *list, FieldSet::Ghost, Shift{axis, offset}), FieldSet::Ghost);
    for (std::size_t k = 0; k < list->size(); ++k) {
      image_source_.push_back((*list)[k]);
      image_target_.push_back(static_cast<std::uint32_t>(first + k));
    }
  }
}

void Halo::refresh(ParticleStore& p, SlabTransport& transport) {
  Bytes from_left, from_right;
  transport.exchange(pack_particles(p, send_left_, FieldSet::Refresh),
                     pack_particles(p, send_right_, FieldSet::Refresh), from_left, from_right);
  unpack_into(p, from_left, FieldSet::Refresh, slots_left_);
  unpack_into(p, from_right, FieldSet::Refresh, slots_right_);
  // Images in creation order (an image of an image copies after its source was refreshed).
  for (auto& f : p.fields()) {
    if (!in_set(f, FieldSet::Refresh)) continue;
    char* data = f.bytes();
    for (std::size_t k = 0; k < image_source_.size(); ++k)
      std::copy_n(data + image_source_[k] * f.elem_size, f.elem_size, data + image_target_[k] * f.elem_size);
  }
}

std::int64_t migrate(ParticleStore& p, const std::vector<int>& faces, const Lattice& lattice,
                     SlabTransport& transport) {
  // One hop towards the owner per round (the plan shared with the device-resident path).
  const std::vector<std::int8_t> hops = migration_hops(faces, transport.slab(), lattice.periodic[0]);
  p.resize(p.owned());
  std::int64_t moved_total = 0;
  for (;;) {
    std::vector<std::uint32_t> go_left, go_right;
    std::vector<std::uint8_t> leaving(p.owned(), 0);
    for (std::size_t i = 0; i < p.owned(); ++i) {
      const std::int8_t hop = hops[lattice.cell_of(p.pos[0][i], 0)];
      if (hop == 0) continue;
      (hop < 0 ? go_left : go_right).push_back(static_cast<std::uint32_t>(i));
      leaving[i] = 1;
    }
    const std::int64_t moved = transport.sum(static_cast<std::int64_t>(go_left.size() + go_right.size()));
    if (moved == 0) break;
    moved_total += moved;
    Bytes from_left, from_right;
    transport.exchange(pack_particles(p, go_left, FieldSet::All), pack_particles(p, go_right, FieldSet::All),
                       from_left, from_right);
    p.remove_owned_if(leaving);
    unpack_append(p, from_left, FieldSet::All);
    unpack_append(p, from_right, FieldSet::All);
    p.set_owned(p.size());
  }
  return moved_total;
}

}  // namespace spate
