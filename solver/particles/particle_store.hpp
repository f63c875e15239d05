#pragma once
// Structure-of-arrays particle storage on the host: float32 fields, one array per component.
// Particles [0, owned) belong to this slab, [owned, size) are ghosts (halo copies and periodic
// images). Every array is listed in `fields()` so that sorting, migration, halos and I/O treat all
// of them alike; a new field is added in one place.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <string_view>
#include <utility>
#include <vector>

#include "particle_memory.hpp"

namespace spate {

struct FieldRef {
  std::string_view name;
  void* data;            // points at a ParticleArray<T>
  std::size_t elem_size; // sizeof(T)
  bool ghost;            // copied into halo ghosts
  bool checkpoint;       // part of the restartable state
  void (*resize)(void*, std::size_t);
  char* (*storage)(void*);
  char* bytes() const { return storage(data); }  // start of the vector's storage
};

class ParticleStore {
 public:
  explicit ParticleStore(int dim = 3) : dim_(dim) {}

  int dim() const { return dim_; }
  std::size_t size() const { return id.size(); }
  std::size_t owned() const { return owned_; }
  std::size_t ghosts() const { return size() - owned_; }
  void set_owned(std::size_t n) { owned_ = n; }

  void resize(std::size_t n);
  // All fields, in a fixed order. Position/velocity/acceleration components beyond dim are empty.
  std::vector<FieldRef> fields();
  // Bytes held per particle by the per-particle arrays (the headline memory figure).
  std::size_t bytes_per_particle() const;

  // Keep particles [first, first + perm.size()) reordered so that new slot k holds old perm[k].
  void permute(std::size_t first, std::span<const std::uint32_t> perm);
  // Append particle `src` of `from` (all fields) at the end.
  void append_from(const ParticleStore& from, std::size_t src);
  // Drop particles whose flag is set, among [0, owned); ghosts are discarded too.
  void remove_owned_if(const std::vector<std::uint8_t>& flag);
  // Swap old and new rates (the integrator keeps the previous step's rates).
  void swap_rates();

  // Fields (public: the drivers in backend/ read them directly; names as SPH users say them).
  // Their memory comes from particle_memory.hpp (the heap, or the arena an in-situ helper maps).
  ParticleArray<float> pos[3];
  ParticleArray<float> vel[3];
  ParticleArray<float> acc[3];
  ParticleArray<float> acc_prev[3];
  ParticleArray<float> density;
  ParticleArray<float> pressure;
  ParticleArray<float> density_rate;
  ParticleArray<float> density_rate_prev;
  ParticleArray<std::uint32_t> id;
  ParticleArray<std::uint8_t> kind;

 private:
  int dim_;
  std::size_t owned_ = 0;
  std::vector<std::uint32_t> scratch_;  // permute(): one word per particle for every field type
  std::vector<std::pair<std::uint32_t, std::uint32_t>> runs_;  // permute(): the slot ranges that change
};

}  // namespace spate
