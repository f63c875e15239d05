#include "particle_pack.hpp"

#include <cstring>
#include <stdexcept>

namespace spate {

bool in_set(const FieldRef& f, FieldSet set) {
  switch (set) {
    case FieldSet::All: return f.has(kMigrated);
    case FieldSet::Ghost: return f.has(kGhost);
    case FieldSet::Refresh: return f.has(kRefreshed);
  }
  return false;
}

std::size_t packed_count(const Bytes& buffer) {
  if (buffer.empty()) return 0;
  std::uint64_t n = 0;
  std::memcpy(&n, buffer.data(), sizeof n);
  return n;
}

Bytes pack_particles(ParticleStore& p, std::span<const std::uint32_t> indices, FieldSet set, Shift shift) {
  const std::uint64_t n = indices.size();
  std::size_t bytes = sizeof n;
  auto fields = p.fields();
  for (auto& f : fields)
    if (in_set(f, set)) bytes += n * f.elem_size;
  Bytes out(bytes);
  char* w = out.data();
  std::memcpy(w, &n, sizeof n);
  w += sizeof n;
  for (auto& f : fields) {
    if (!in_set(f, set)) continue;
    const char* src = f.bytes();
    const std::size_t s = f.elem_size;
    for (std::uint64_t k = 0; k < n; ++k) std::memcpy(w + k * s, src + indices[k] * s, s);
    if (shift.axis >= 0 && f.data == static_cast<void*>(&p.pos[shift.axis])) {
      auto* x = reinterpret_cast<float*>(w);
      for (std::uint64_t k = 0; k < n; ++k) {
        float v;
        std::memcpy(&v, x + k, sizeof v);
        v = shift.apply(v);
        std::memcpy(x + k, &v, sizeof v);
      }
    }
    w += n * s;
  }
  return out;
}

namespace {
template <class Slot>
void unpack(ParticleStore& p, const Bytes& buffer, FieldSet set, Slot slot) {
  const std::size_t n = packed_count(buffer);
  if (n == 0) return;
  const char* r = buffer.data() + sizeof(std::uint64_t);
  for (auto& f : p.fields()) {
    if (!in_set(f, set)) continue;
    if (r + n * f.elem_size > buffer.data() + buffer.size()) throw std::runtime_error("truncated particle buffer");
    char* dst = f.bytes();
    for (std::size_t k = 0; k < n; ++k) std::memcpy(dst + slot(k) * f.elem_size, r + k * f.elem_size, f.elem_size);
    r += n * f.elem_size;
  }
}
}  // namespace

std::size_t unpack_append(ParticleStore& p, const Bytes& buffer, FieldSet set) {
  const std::size_t n = packed_count(buffer);
  if (n == 0) return 0;
  const std::size_t first = p.size();
  p.resize(first + n);
  unpack(p, buffer, set, [first](std::size_t k) { return first + k; });
  return n;
}

void unpack_into(ParticleStore& p, const Bytes& buffer, FieldSet set, std::span<const std::uint32_t> slots) {
  if (packed_count(buffer) != slots.size()) throw std::runtime_error("halo refresh: count mismatch");
  unpack(p, buffer, set, [&](std::size_t k) { return slots[k]; });
}

}  // namespace spate
