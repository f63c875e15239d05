#include "halo.hpp"

#include <algorithm>
#include <numeric>
#include <stdexcept>

#include "slab_layout.hpp"
#include "slab_plan.hpp"

namespace spate {

namespace {
// Owned particles (in storage order) of the first and last owned x columns.
void edge_columns(const ParticleStore& p, const CellGrid& grid, std::vector<std::uint32_t>& first,
                  std::vector<std::uint32_t>& last) {
  first.clear();
  last.clear();
  const Lattice& L = grid.lattice();
  const float* x = p.pos[0].data();
  for (std::size_t i = 0; i < p.owned(); ++i) {
    const int c = L.cell_of(x[i], 0);
    if (c == grid.owned_lo()) first.push_back(static_cast<std::uint32_t>(i));
    if (c == grid.owned_hi() - 1) last.push_back(static_cast<std::uint32_t>(i));
  }
}

// `sent` lists the storage positions of one owned x column, in increasing order, from before the
// owned sort; rewrites them as positions after it, keeping the list's order (the order in which
// the neighbour received them). After the sort the column is one contiguous range.
void follow_sort(std::vector<std::uint32_t>& sent, const CellGrid& grid, int column) {
  if (sent.empty()) return;
  const Lattice& L = grid.lattice();
  const std::uint32_t per_column = (L.dim >= 2 ? L.cells[1] : 1) * (L.dim >= 3 ? L.cells[2] : 1);
  const std::uint32_t first_cell = static_cast<std::uint32_t>(column - grid.owned_lo()) * per_column;
  const std::uint32_t b = grid.begin(first_cell), e = grid.begin(first_cell + per_column);
  if (e - b != sent.size()) throw std::logic_error("Halo: edge column changed during the owned sort");
  const auto& perm = grid.owned_permutation();
  std::vector<std::uint32_t> now(sent.size());
  for (std::uint32_t k = b; k < e; ++k) {
    const auto at = std::lower_bound(sent.begin(), sent.end(), perm[k]) - sent.begin();
    now[static_cast<std::size_t>(at)] = k;
  }
  sent.swap(now);
}
}  // namespace

void Halo::send(ParticleStore& p, const CellGrid& grid, SlabTransport& transport) {
  const Lattice& L = grid.lattice();
  const int s = transport.slab();
  const bool has_left = transport.left_of(s) >= 0, has_right = transport.right_of(s) >= 0;
  // Wrapping across the periodic x boundary shifts the copy by the period, computed by the owner
  // so that every split produces the same float.
  Shift to_left, to_right;
  if (has_left && grid.owned_lo() == 0) to_left = periodic_shift(L, 0, true);
  if (has_right && grid.owned_hi() == L.cells[0]) to_right = periodic_shift(L, 0, false);
  p.resize(p.owned());  // ghosts are stale once owned particles moved
  edge_columns(p, grid, send_left_, send_right_);
  if (!has_left) send_left_.clear();
  if (!has_right) send_right_.clear();
  transport.exchange(pack_particles(p, send_left_, FieldSet::Ghost, to_left),
                     pack_particles(p, send_right_, FieldSet::Ghost, to_right), from_left_, from_right_);
}

void Halo::receive(ParticleStore& p, CellGrid& grid) {
  const Lattice& L = grid.lattice();
  grid.sort_owned(p);
  // The scan took the edge columns in storage order; the refresh sends them in that same order.
  follow_sort(send_left_, grid, grid.owned_lo());
  follow_sort(send_right_, grid, grid.owned_hi() - 1);
  const std::size_t owned = p.owned();
  const std::size_t n_left = unpack_append(p, from_left_, FieldSet::Ghost);
  const std::size_t n_right = unpack_append(p, from_right_, FieldSet::Ghost);
  Bytes().swap(from_left_);  // freed, not kept: they are as large as the ghosts' fields
  Bytes().swap(from_right_);

  image_source_.clear();
  image_target_.clear();
  image_local_.clear();
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
    const std::size_t first = p.size();
    unpack_append(p, pack_particles(p, *list, FieldSet::Ghost, periodic_shift(L, axis, list == &low)), FieldSet::Ghost);
    for (std::size_t k = 0; k < list->size(); ++k) {
      image_source_.push_back((*list)[k]);
      image_target_.push_back(static_cast<std::uint32_t>(first + k));
      image_local_.push_back(grid.owns_column(L.cell_of(p.pos[0][(*list)[k]], 0)) ? 1 : 0);
    }
  }
}

void Halo::begin_refresh(ParticleStore& p, SlabTransport& transport) {
  transport.post(pack_particles(p, send_left_, FieldSet::Refresh), pack_particles(p, send_right_, FieldSet::Refresh));
  refresh_images(p, true);
}

void Halo::finish_refresh(ParticleStore& p, SlabTransport& transport) {
  Bytes from_left, from_right;
  transport.collect(from_left, from_right);
  unpack_into(p, from_left, FieldSet::Refresh, slots_left_);
  unpack_into(p, from_right, FieldSet::Refresh, slots_right_);
  refresh_images(p, false);
}

// Images in creation order (an image of an image copies after its source was refreshed; both lie
// in the same x column, so in the same half).
void Halo::refresh_images(ParticleStore& p, bool local) {
  for (auto& f : p.fields()) {
    if (!in_set(f, FieldSet::Refresh)) continue;
    char* data = f.bytes();
    for (std::size_t k = 0; k < image_source_.size(); ++k)
      if (image_local_[k] == (local ? 1 : 0))
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
