#include "particle_store.hpp"

#include "../backend/cpu/parallel.hpp"

#include <algorithm>
#include <atomic>
#include <list>
#include <cstring>
#include <mutex>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>

namespace spate {

namespace {
template <class T>
void resize_vector(void* v, std::size_t n) {
  static_cast<FieldVector<T>*>(v)->resize(n);
}
template <class T>
char* vector_storage(void* v) {
  return reinterpret_cast<char*>(static_cast<FieldVector<T>*>(v)->data());
}
template <class T>
FieldRef ref(const FieldSpec& spec, int component, FieldVector<T>& v) {
  return FieldRef{&spec, component, spec.names[component], &v, sizeof(T), &resize_vector<T>, &vector_storage<T>};
}
template <class T>
void add(std::vector<FieldRef>& out, const FieldSpec& spec, int, FieldVector<T>& v) {
  out.push_back(ref(spec, 0, v));
}
template <class T>
void add(std::vector<FieldRef>& out, const FieldSpec& spec, int dim, FieldVector<T> (&v)[3]) {
  for (int k = 0; k < dim; ++k) out.push_back(ref(spec, k, v[k]));
}

std::mutex& extensions_mutex() {
  static std::mutex m;
  return m;
}
std::list<FieldSpec>& extension_list() {
  static std::list<FieldSpec> list;  // stable addresses: FieldRefs point at the entries
  return list;
}

// Reorders only the runs of slots whose particle changes (perm[k] != k): between two steps most
// fluid stays in its cell and static walls never move, so most of a sorted slab keeps its place.
// The moved slots map onto each other (the fixed ones are fixed points of a bijection), so
// gathering all runs before writing any back is a complete permutation. One 32-bit scratch word
// per particle serves every field type (bit copies), so the scratch costs 4 bytes per particle.
template <std::size_t Size>
void permute_runs(char* base, std::size_t first, std::span<const std::uint32_t> perm,
                  const std::vector<std::pair<std::uint32_t, std::uint32_t>>& runs, std::vector<std::uint32_t>& scratch) {
  static_assert(Size <= sizeof(std::uint32_t));
  if (!base) return;
  char* data = base + first * Size;
  for (const auto& [b, e] : runs) {
#pragma omp parallel for schedule(static) if (e - b > cpu::cheap_grain())
    for (std::uint32_t k = b; k < e; ++k) {
      std::uint32_t word = 0;
      std::memcpy(&word, data + std::size_t{perm[k]} * Size, Size);
      scratch[k] = word;
    }
  }
  for (const auto& [b, e] : runs) {
#pragma omp parallel for schedule(static) if (e - b > cpu::cheap_grain())
    for (std::uint32_t k = b; k < e; ++k) std::memcpy(data + std::size_t{k} * Size, &scratch[k], Size);
  }
}
}  // namespace

bool FieldRef::builtin() const {
  return spec >= std::begin(kParticleFields) && spec < std::end(kParticleFields);
}

FieldExtension::FieldExtension(const FieldSpec& spec) {
  std::lock_guard lock(extensions_mutex());
  for (const FieldSpec& f : kParticleFields)
    if (f.member == spec.member) throw std::logic_error("FieldExtension: '" + std::string(spec.member) + "' is a registry field");
  for (const FieldSpec& f : extension_list())
    if (f.member == spec.member) throw std::logic_error("FieldExtension: '" + std::string(spec.member) + "' is registered twice");
  extension_list().push_back(spec);
}

FieldExtension::~FieldExtension() {
  std::lock_guard lock(extensions_mutex());
  extension_list().pop_back();
}

std::vector<const FieldSpec*> field_extensions() {
  std::lock_guard lock(extensions_mutex());
  std::vector<const FieldSpec*> out;
  for (const FieldSpec& f : extension_list()) out.push_back(&f);
  return out;
}

namespace {
// Runs holding each optional group (bit k of kOptionalGroups counts in users[k]).
std::atomic<int>& optional_users(int bit) {
  static std::atomic<int> n[16]{};
  return n[bit];
}
template <class F>
void for_each_group_bit(std::uint16_t groups, F&& f) {
  for (int bit = 0; bit < 16; ++bit)
    if (groups & kOptionalGroups & (1u << bit)) f(bit);
}
}  // namespace

OptionalFields::OptionalFields(FieldGroups groups) : groups_(static_cast<std::uint16_t>(groups)) {
  for_each_group_bit(groups_, [](int bit) { ++optional_users(bit); });
}
OptionalFields::~OptionalFields() {
  for_each_group_bit(groups_, [](int bit) { --optional_users(bit); });
}
std::uint16_t optional_field_groups_enabled() {
  std::uint16_t g = 0;
  for_each_group_bit(kOptionalGroups, [&](int bit) {
    if (optional_users(bit) > 0) g |= static_cast<std::uint16_t>(1u << bit);
  });
  return g;
}
bool optional_fields_enabled() { return (optional_field_groups_enabled() & kOptional) != 0; }

ParticleStore::ParticleStore(int dim) : dim_(dim), groups_(optional_field_groups_enabled()) {
  for (const FieldSpec* spec : field_extensions()) extensions_.push_back(Extension{spec, {}, {}});
}

std::vector<FieldRef> ParticleStore::fields() {
  std::vector<FieldRef> f;
  f.reserve(3 * kBuiltinFieldCount + 3 * extensions_.size());
#define SPATE_STORE_REF(member, ...) \
  if (carries(kParticleFields[kField_##member])) add(f, kParticleFields[kField_##member], dim_, member);
  SPATE_PARTICLE_FIELDS(SPATE_STORE_REF)
#undef SPATE_STORE_REF
  for (Extension& e : extensions_) {
    const int n = e.spec->components(dim_);
    for (int k = 0; k < n; ++k) f.push_back(e.spec->elem_size() == 1 ? ref(*e.spec, k, e.bytes[k]) : ref(*e.spec, k, e.words[k]));
  }
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
  for (const FieldRef& f : fields()) {
    if (f.spec->scratch()) continue;
    if (f.elem_size == 4) permute_runs<4>(f.bytes(), first, perm, runs_, scratch_);
    else permute_runs<1>(f.bytes(), first, perm, runs_, scratch_);
  }
}

void ParticleStore::append_from(const ParticleStore& from, std::size_t src) {
  auto& other = const_cast<ParticleStore&>(from);
  auto src_fields = other.fields();
  const std::size_t n = size();
  resize(n + 1);
  auto dst_fields = fields();
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

std::vector<ExportedField> exported_fields(ParticleStore& p) {
  std::vector<ExportedField> out;
  for (const FieldRef& f : p.fields()) {
    if (!f.has(kExported)) continue;
    if (out.empty() || out.back().spec != f.spec) out.push_back(ExportedField{f.spec, 0, {nullptr, nullptr, nullptr}});
    out.back().data[f.component] = f.bytes();
    ++out.back().components;
  }
  return out;
}

void ParticleStore::swap_rates() {
  for (int k = 0; k < 3; ++k) std::swap(acc[k], acc_prev[k]);
  std::swap(density_rate, density_rate_prev);
  std::swap(temperature_rate, temperature_rate_prev);  // empty without heat transfer
}

}  // namespace spate
