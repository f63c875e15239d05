#pragma once
// Where the particle field arrays live: the one place that decides it (ParticleStore's arrays
// are FieldVector<T> = std::vector<T, ParticleAllocator<T>>, particle_store.hpp).
//
// By default they live on the heap. A process that hands its particles to an in-situ helper
// process (ParaView Catalyst runs there, adaptors/catalyst/insitu_helper.hpp) first calls
// share_particle_memory(): from then on every particle array comes from one arena backed by a
// memfd that the helper maps at the same address. The helper's VTK arrays then point at the very
// pages the solver writes (zero copy across the process boundary), and nothing the helper does
// (a segfault, an abort, exit()) can corrupt or end the solver. The arena is reserved virtual
// address space; pages are only committed when written, and returned when an array is freed.
#include <cstddef>
#include <cstdint>
#include <new>

namespace spate {

// The shared arena, as a helper maps it.
struct SharedParticleMemory {
  int fd = -1;              // the memfd (close-on-exec: a spawner hands it on explicitly)
  std::uintptr_t base = 0;  // where this process mapped it (the helper maps it at the same place)
  std::size_t size = 0;     // bytes reserved
  bool contains(const void* p) const {
    const auto a = reinterpret_cast<std::uintptr_t>(p);
    return a >= base && a < base + size;
  }
};

// Puts every particle array allocated from now on into the shared arena (idempotent). Call it
// before the particles are created: arrays allocated earlier stay on the heap (and are freed
// there). Throws std::runtime_error when the arena cannot be made (no memfd, no address space).
const SharedParticleMemory& share_particle_memory();
// The arena when particle memory is shared, else nullptr.
const SharedParticleMemory* shared_particle_memory();
// Bytes of the arena handed out now (for tests and reports); 0 when not shared.
std::size_t shared_particle_bytes_in_use();

namespace detail {
void* allocate_particle_bytes(std::size_t bytes);
void free_particle_bytes(void* p, std::size_t bytes) noexcept;
}  // namespace detail

// Stateless, so every array of a type is interchangeable (swap and move as std::vector).
template <class T>
struct ParticleAllocator {
  using value_type = T;
  ParticleAllocator() noexcept = default;
  template <class U>
  ParticleAllocator(const ParticleAllocator<U>&) noexcept {}
  T* allocate(std::size_t n) { return static_cast<T*>(detail::allocate_particle_bytes(n * sizeof(T))); }
  void deallocate(T* p, std::size_t n) noexcept { detail::free_particle_bytes(p, n * sizeof(T)); }
  template <class U>
  bool operator==(const ParticleAllocator<U>&) const noexcept {
    return true;
  }
};

}  // namespace spate
