#include "host_slab_arrays.hpp"

#include <algorithm>
#include <cstring>
#include <numeric>
#include <stdexcept>

#include "../backend/cpu/parallel.hpp"

namespace spate {

namespace {
// Copies fields `set` of `from` [0, n) into `to` (all of `to`'s entries [0, n) afterwards).
void copy_fields(ParticleStore& from, ParticleStore& to, FieldSet set, std::size_t first, std::size_t last) {
  auto a = from.fields(), b = to.fields();
  for (std::size_t f = 0; f < a.size(); ++f)
    if (in_set(a[f], set) && last > first)
      std::memcpy(b[f].bytes() + first * b[f].elem_size, a[f].bytes() + first * a[f].elem_size, (last - first) * a[f].elem_size);
}
}  // namespace

void HostSlabArrays::set_id_bound(std::uint32_t bound) {
  require_ids_below(store_->id, bound);
  id_bound_ = bound;
}

void HostSlabArrays::upload(const ParticleStore& host) {
  require_ids_below(host.id, id_bound_);
  if (&host != store_) *store_ = host;
  keys_.assign(store_->size(), 0);
}

void HostSlabArrays::download(ParticleStore& host, CellGrid& grid) {
  if (host.dim() != store_->dim()) throw std::logic_error("HostSlabArrays::download: a store of another dimension");
  // Before anything changes: throws on a stale geometry. A shared store and grid are the truth already.
  if (!table_.empty() && &grid != grid_) grid.assign_starts(grid_->view(), table_);
  if (&host == store_) return;
  host.resize(store_->size());
  host.set_owned(store_->owned());
  copy_fields(*store_, host, FieldSet::All, 0, store_->owned());
  copy_fields(*store_, host, FieldSet::Ghost, store_->owned(), store_->size());
}

void HostSlabArrays::truncate(std::size_t n) {
  store_->resize(n);
  keys_.resize(n);
}

void HostSlabArrays::compute_keys(const CellGrid& geometry, std::size_t first, std::size_t last, bool migrating) {
  keys_.resize(store_->size());
  const CellGridView v = geometry.view();
  const Lattice& L = geometry.lattice();
  const std::int8_t* hops = migrating ? hops_.data() : nullptr;
  const int d = store_->dim();
  const auto n = static_cast<std::int64_t>(last - first);
#pragma omp parallel for schedule(static) if (n > cpu::cheap_grain())
  for (std::int64_t k = 0; k < n; ++k) {
    const std::size_t i = first + static_cast<std::size_t>(k);
    keys_[i] = particle_key(v, L, hops, store_->pos[0][i], d >= 2 ? store_->pos[1][i] : 0.0f, d >= 3 ? store_->pos[2][i] : 0.0f);
  }
}

// A counting sort by key, then an insertion sort by id inside each key (the order of the previous
// step is nearly right): the order of a stable sort by (key, id), in linear time.
void HostSlabArrays::sort_by_key(std::size_t first, std::size_t last) {
  const std::size_t n = last - first;
  perm_.resize(n);
  perm_first_ = first;
  if (n == 0) return;
  std::uint32_t* key = keys_.data() + first;
  const std::uint32_t* id = store_->id.data() + first;
  const std::uint32_t bins = *std::max_element(key, key + n) + 1;
  counts_.assign(std::size_t{bins} + 1, 0u);
  for (std::size_t i = 0; i < n; ++i) ++counts_[key[i] + 1];
  for (std::uint32_t b = 0; b < bins; ++b) counts_[b + 1] += counts_[b];
  for (std::size_t i = 0; i < n; ++i) perm_[counts_[key[i]]++] = static_cast<std::uint32_t>(i);
  // counts_[b] is now the end of bin b.
#pragma omp parallel for schedule(dynamic, 256) if (static_cast<std::int64_t>(n) > cpu::cheap_grain())
  for (std::int64_t b = 0; b < static_cast<std::int64_t>(bins); ++b) {
    const std::uint32_t e = counts_[b], s = b == 0 ? 0u : counts_[b - 1];
    for (std::uint32_t k = s + 1; k < e; ++k) {
      const std::uint32_t v = perm_[k];
      std::uint32_t m = k;
      for (; m > s && id[perm_[m - 1]] > id[v]; --m) perm_[m] = perm_[m - 1];
      perm_[m] = v;
    }
  }
  store_->permute(first, perm_);
  for (std::uint32_t b = 0, s = 0; b < bins; s = counts_[b++]) std::fill(key + s, key + counts_[b], b);
}

void HostSlabArrays::build_table(const CellGrid& geometry) {
  if (grid_->lattice().cells[0] != geometry.lattice().cells[0] || grid_->owned_lo() != geometry.owned_lo() ||
      grid_->owned_hi() != geometry.owned_hi() || grid_->cell_count() != geometry.cell_count())
    grid_->configure(geometry.lattice(), geometry.owned_lo(), geometry.owned_hi());
  const KeyBins bins{geometry.cell_count()};
  // The first particle of every bin, in one pass over the non-decreasing keys (a lower bound per bin).
  table_.resize(bins.table_entries());
  const auto n = static_cast<std::uint32_t>(keys_.size());
  std::uint32_t b = 0;
  for (std::uint32_t i = 0; i < n; ++i)
    for (; b <= keys_[i] && b < bins.table_entries(); ++b) table_[b] = i;
  for (; b < bins.table_entries(); ++b) table_[b] = n;
  grid_->assign_starts(geometry.view(), table_);
}

std::vector<std::uint32_t> HostSlabArrays::table_entries(const TableRead& read) {
  std::vector<std::uint32_t> out(read.count);
  for (std::uint32_t k = 0; k < read.count; ++k) out[k] = table_.at(read.first + k * read.stride);
  return out;
}

void HostSlabArrays::stage(Side side, FieldSet set, ParticleRange range, Shift shift) {
  std::vector<std::uint32_t> indices(range.count);
  std::iota(indices.begin(), indices.end(), static_cast<std::uint32_t>(range.first));
  outbox_[side] = pack_particles(*store_, indices, set, shift);
}

std::array<std::size_t, 2> HostSlabArrays::exchange(SlabTransport& t, FieldSet) {
  t.exchange(outbox_[kLeft], outbox_[kRight], inbox_[kLeft], inbox_[kRight]);
  return {packed_count(inbox_[kLeft]), packed_count(inbox_[kRight])};
}

void HostSlabArrays::append_received(Side side, FieldSet set) {
  unpack_append(*store_, inbox_[side], set);
  keys_.resize(store_->size());
}

void HostSlabArrays::scatter_received(Side side) { unpack_into(*store_, inbox_[side], FieldSet::Refresh, slots_[side]); }

void HostSlabArrays::forget_images() {
  for (auto& axis : images_)
    for (auto& im : axis) im.source.clear(), im.target.clear();
}

void HostSlabArrays::make_images(const CellGrid& geometry, int axis) {
  const Lattice& L = geometry.lattice();
  const std::size_t n = store_->size();
  for (const ImagePart part : {ImagePart::Local, ImagePart::Halo}) {
    Images& im = images_[axis][static_cast<int>(part)];
    for (const int layer : {0, L.cells[axis] - 1}) {
      std::vector<std::uint32_t> list;
      for (std::size_t i = 0; i < n; ++i)
        if (L.cell_of(store_->pos[axis][i], axis) == layer &&
            geometry.owns_column(L.cell_of(store_->pos[0][i], 0)) == (part == ImagePart::Local))
          list.push_back(static_cast<std::uint32_t>(i));
      const std::size_t first = store_->size();
      unpack_append(*store_, pack_particles(*store_, list, FieldSet::Ghost, periodic_shift(L, axis, layer == 0)), FieldSet::Ghost);
      for (std::size_t k = 0; k < list.size(); ++k) {
        im.source.push_back(list[k]);
        im.target.push_back(static_cast<std::uint32_t>(first + k));
      }
    }
  }
  keys_.resize(store_->size());
}

void HostSlabArrays::record_halo_slots(std::size_t left, std::size_t right) {
  const std::size_t owned = store_->owned();
  if (perm_first_ != owned || perm_.size() != store_->size() - owned)
    throw std::logic_error("HostSlabArrays: record_halo_slots must follow the ghost sort");
  std::vector<std::uint32_t> slot_of(perm_.size());
  for (std::size_t k = 0; k < perm_.size(); ++k) slot_of[perm_[k]] = static_cast<std::uint32_t>(owned + k);
  auto slot = [&](std::uint32_t absolute) { return absolute < owned ? absolute : slot_of[absolute - owned]; };
  slots_[kLeft].resize(left);
  slots_[kRight].resize(right);
  for (std::size_t k = 0; k < left; ++k) slots_[kLeft][k] = slot_of[k];
  for (std::size_t k = 0; k < right; ++k) slots_[kRight][k] = slot_of[left + k];
  for (auto& axis : images_)
    for (auto& im : axis) {
      for (auto& s : im.source) s = slot(s);
      for (auto& s : im.target) s = slot(s);
    }
}

void HostSlabArrays::refresh_images(ImagePart part) {
  for (auto& f : store_->fields()) {
    if (!in_set(f, FieldSet::Refresh)) continue;
    char* data = f.bytes();
    for (auto& axis : images_) {
      const Images& im = axis[static_cast<int>(part)];
      for (std::size_t k = 0; k < im.source.size(); ++k)
        std::memcpy(data + im.target[k] * f.elem_size, data + im.source[k] * f.elem_size, f.elem_size);
    }
  }
}

std::vector<std::uint32_t> HostSlabArrays::remove_escaped(const OpenSides& open) {
  std::vector<std::uint32_t> ids;
  if (!open.open) return ids;
  std::vector<std::uint8_t> gone;
  for (std::size_t i = 0; i < store_->owned(); ++i) {
    float x[3] = {0, 0, 0};
    for (int a = 0; a < store_->dim(); ++a) x[a] = store_->pos[a][i];
    if (!escaped(open, store_->dim(), store_->material[i], x)) continue;
    if (gone.empty()) gone.assign(store_->owned(), 0);
    gone[i] = 1, ids.push_back(store_->id[i]);
  }
  if (ids.empty()) return ids;
  store_->remove_owned_if(gone);
  keys_.resize(store_->size());
  std::sort(ids.begin(), ids.end());
  return ids;
}

std::uint32_t HostSlabArrays::wrap_and_find_position_fault(const Lattice& L) {
  std::uint32_t lowest = kNoFault;
  for (std::size_t i = 0; i < store_->owned(); ++i) {
    for (int a = 0; a < L.dim; ++a) {
      wrap_periodic(L, store_->pos[a][i], a);
      if (position_fault(L, store_->pos[a][i], a) != PositionFault::None) lowest = std::min(lowest, store_->id[i]);
    }
  }
  return lowest;
}

std::uint32_t HostSlabArrays::find_unhealthy(const HealthLimits& h) {
  std::uint32_t lowest = kNoFault;
  const int d = store_->dim();
  for (std::size_t i = 0; i < store_->owned(); ++i) {
    if (!h.checked(store_->material[i])) continue;
    float x[3] = {0, 0, 0}, v[3] = {0, 0, 0};
    for (int a = 0; a < d; ++a) x[a] = store_->pos[a][i], v[a] = store_->vel[a][i];
    if (!healthy(h, state_finite(d, x, v, store_->density[i]), store_->density[i], store_->material[i])) lowest = std::min(lowest, store_->id[i]);
  }
  return lowest;
}

}  // namespace spate
