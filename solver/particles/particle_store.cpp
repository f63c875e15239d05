#include "particle_store.hpp"

#include "../backend/cpu/parallel.hpp"

#include <algorithm>
#include <cstring>
#include <type_traits>
#include <utility>

namespace spate {

namespace {
template <class T>
void resize_vector(void* v, std::size_t n) {
  static_cast<ParticleArray<T>*>(v)->resize(n);
}
template <class T>
char* vector_storage(void* v) {
  return reinterpret_cast<char*>(static_cast<ParticleArray<T>*>(v)->data());
}
template <class T>
FieldRef ref(std::string_view name, ParticleArray<T>& v, bool ghost, bool checkpoint) {
  return FieldRef{name, &v, sizeof(T), ghost, checkpoint, &resize_vector<T>, &vector_storage<T>};
}
// Reorders only the runs of slots whose particle changes (perm[k] != k): between two steps walls
// never move and most fluid stays in its cell, so most of a sorted slab keeps its place. The moved
// slots map onto each other (the fixed ones are fixed points of a bijection), so gathering all
// runs before writing any back is a complete permutation. One 32-bit scratch word per particle
// serves every field type (bit copies), so the scratch costs 4 bytes per particle.
template <class T>
void permute_runs(ParticleArray<T>& v, std::size_t first, std::span<const std::uint32_t> perm,
                  const std::vector<std::pair<std::uint32_t, std::uint32_t>>& runs, std::vector<std::uint32_t>& scratch) {
  static_assert(sizeof(T) <= sizeof(std::uint32_t) && std::is_trivially_copyable_v<T>);
  if (v.empty()) return;
  T* data = v.data() + first;
  for (const auto& [b, e] : runs) {
#pragma omp parallel for schedule(static) if (e - b > cpu::kCheapGrain)
    for (std::uint32_t k = b; k < e; ++k) {
      std::uint32_t word = 0;
      std::memcpy(&word, data + perm[k], sizeof(T));
      scratch[k] = word;
    }
  }
  for (const auto& [b, e] : runs) {
#pragma omp parallel for schedule(static) if (e - b > cpu::kCheapGrain)
    for (std::uint32_t k = b; k < e; ++k) std::memcpy(data + k, &scratch[k], sizeof(T));
  }
}
}  // namespace

std::vector<FieldRef> ParticleStore::fields() {
  static constexpr std::string_view pos_names[3] = {"x", "y", "z"};
  static constexpr std::string_view vel_names[3] = {"vx", "vy", "vz"};
  static constexpr std::string_view acc_names[3] = {"ax", "ay", "az"};
  static constexpr std::string_view accp_names[3] = {"ax_prev", "ay_prev", "az_prev"};
  std::vector<FieldRef> f;
  for (int k = 0; k < dim_; ++k) f.push_back(ref(pos_names[k], pos[k], true, true));
  for (int k = 0; k < dim_; ++k) f.push_back(ref(vel_names[k], vel[k], true, true));
  f.push_back(ref("density", density, true, true));
  f.push_back(ref("pressure", pressure, true, false));
  f.push_back(ref("id", id, true, true));
  f.push_back(ref("kind", kind, true, true));
  for (int k = 0; k < dim_; ++k) f.push_back(ref(acc_names[k], acc[k], false, true));
  f.push_back(ref("density_rate", density_rate, false, true));
  for (int k = 0; k < dim_; ++k) f.push_back(ref(accp_names[k], acc_prev[k], false, false));
  f.push_back(ref("density_rate_prev", density_rate_prev, false, false));
  return f;
}

void ParticleStore::resize(std::size_t n) {
  for (auto& f : fields()) f.resize(f.data, n);
  owned_ = std::min(owned_, n);
}

std::size_t ParticleStore::bytes_per_particle() const {
  std::size_t b = 0;
  for (auto& f : const_cast<ParticleStore*>(this)->fields()) b += f.elem_size;
  // The cell sort keeps a key and a permutation per particle, and permute() one scratch word.
  return b + 3 * sizeof(std::uint32_t);
}

void ParticleStore::permute(std::size_t first, std::span<const std::uint32_t> perm) {
  const auto n = static_cast<std::uint32_t>(perm.size());
  runs_.clear();
  for (std::uint32_t k = 0; k < n;) {
    if (perm[k] == k) {
      ++k;
      continue;
    }
    const std::uint32_t b = k;
    while (k < n && perm[k] != k) ++k;
    // Gaps of fewer than 64 fixed slots join the runs around them (copying a fixed slot is
    // harmless): fewer, longer runs, at most one per 64 particles.
    if (!runs_.empty() && b - runs_.back().second < 64) runs_.back().second = k;
    else runs_.emplace_back(b, k);
  }
  if (runs_.empty()) return;
  scratch_.resize(n);
  for (int k = 0; k < 3; ++k) {
    permute_runs(pos[k], first, perm, runs_, scratch_);
    permute_runs(vel[k], first, perm, runs_, scratch_);
    permute_runs(acc[k], first, perm, runs_, scratch_);
    permute_runs(acc_prev[k], first, perm, runs_, scratch_);
  }
  permute_runs(density, first, perm, runs_, scratch_);
  permute_runs(pressure, first, perm, runs_, scratch_);
  permute_runs(density_rate, first, perm, runs_, scratch_);
  permute_runs(density_rate_prev, first, perm, runs_, scratch_);
  permute_runs(id, first, perm, runs_, scratch_);
  permute_runs(kind, first, perm, runs_, scratch_);
}

void ParticleStore::append_from(const ParticleStore& from, std::size_t src) {
  auto& self = *this;
  auto& other = const_cast<ParticleStore&>(from);
  auto dst_fields = self.fields();
  auto src_fields = other.fields();
  const std::size_t n = size();
  resize(n + 1);
  dst_fields = self.fields();
  for (std::size_t f = 0; f < dst_fields.size(); ++f) {
    const std::size_t s = dst_fields[f].elem_size;
    std::memcpy(dst_fields[f].bytes() + n * s, src_fields[f].bytes() + src * s, s);
  }
}

void ParticleStore::remove_owned_if(const std::vector<std::uint8_t>& flag) {
  std::size_t keep = 0;
  auto fs = fields();
  for (std::size_t i = 0; i < owned_; ++i) {
    if (flag[i]) continue;
    if (keep != i)
      for (auto& f : fs) std::memcpy(f.bytes() + keep * f.elem_size, f.bytes() + i * f.elem_size, f.elem_size);
    ++keep;
  }
  owned_ = keep;
  resize(keep);
}

void ParticleStore::swap_rates() {
  for (int k = 0; k < 3; ++k) std::swap(acc[k], acc_prev[k]);
  std::swap(density_rate, density_rate_prev);
}

}  // namespace spate
