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
  static_cast<std::vector<T>*>(v)->resize(n);
}
template <class T>
char* vector_storage(void* v) {
  return reinterpret_cast<char*>(static_cast<std::vector<T>*>(v)->data());
}
template <class T>
FieldRef ref(std::string_view name, std::vector<T>& v, bool ghost, bool checkpoint) {
  return FieldRef{name, &v, sizeof(T), ghost, checkpoint, &resize_vector<T>, &vector_storage<T>};
}
// One 32-bit scratch word per particle serves every field type (bit copies), so the sort's
// scratch costs 4 bytes per particle, not one array per type.
template <class T>
void permute_range(std::vector<T>& v, std::size_t first, std::span<const std::uint32_t> perm,
                   std::vector<std::uint32_t>& scratch) {
  static_assert(sizeof(T) <= sizeof(std::uint32_t) && std::is_trivially_copyable_v<T>);
  if (v.empty()) return;
  const std::size_t n = perm.size();
  scratch.resize(n);
#pragma omp parallel for schedule(static) if (n > cpu::kCheapGrain)
  for (std::size_t k = 0; k < n; ++k) {
    std::uint32_t word = 0;
    std::memcpy(&word, &v[first + perm[k]], sizeof(T));
    scratch[k] = word;
  }
#pragma omp parallel for schedule(static) if (n > cpu::kCheapGrain)
  for (std::size_t k = 0; k < n; ++k) std::memcpy(&v[first + k], &scratch[k], sizeof(T));
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
  for (int k = 0; k < 3; ++k) {
    permute_range(pos[k], first, perm, scratch_);
    permute_range(vel[k], first, perm, scratch_);
    permute_range(acc[k], first, perm, scratch_);
    permute_range(acc_prev[k], first, perm, scratch_);
  }
  permute_range(density, first, perm, scratch_);
  permute_range(pressure, first, perm, scratch_);
  permute_range(density_rate, first, perm, scratch_);
  permute_range(density_rate_prev, first, perm, scratch_);
  permute_range(id, first, perm, scratch_);
  permute_range(kind, first, perm, scratch_);
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
