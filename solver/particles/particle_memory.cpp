#include "particle_memory.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <unistd.h>

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <map>
#include <mutex>
#include <stdexcept>

namespace spate {

namespace {

constexpr std::size_t kPage = 4096;
// Where the arena is asked to go: far below the shared libraries and stacks (near 0x7f...) and far
// above the program and its heap (near 0x55...), so that a freshly started helper, whose libraries
// land elsewhere, almost always finds the same range free and maps it at the same address.
constexpr std::uintptr_t kPreferredBase = std::uintptr_t{0x2000} << 32;  // 32 TiB

// Reserved address space: four times the machine's memory (the particles cannot use more than the
// memory, and freed arrays leave holes), at most 16 TiB, and at most a quarter of RLIMIT_AS.
std::size_t reservation() {
  const long pages = sysconf(_SC_PHYS_PAGES);
  std::size_t size = 4 * static_cast<std::size_t>(std::max(pages, 1L << 18)) * kPage;
  size = std::min(size, std::size_t{16} << 40);
  rlimit limit{};
  if (getrlimit(RLIMIT_AS, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY)
    size = std::min<std::size_t>(size, limit.rlim_cur / 4);
  return std::max(size / kPage * kPage, std::size_t{1} << 30);
}

// First fit over page-rounded blocks; freed blocks give their pages back (hole punching) and
// merge with free neighbours. Allocations are rare (arrays grow with headroom), so a map is fine.
class Arena {
 public:
  Arena() {
    const int fd = memfd_create("spate-particles", MFD_CLOEXEC);
    if (fd < 0) throw std::runtime_error(fmt::format("shared particle memory: memfd_create: {}", std::strerror(errno)));
    std::size_t size = reservation();
    void* at = MAP_FAILED;
    for (; size >= (std::size_t{1} << 30) && at == MAP_FAILED; size /= 2) {
      if (ftruncate(fd, static_cast<off_t>(size)) != 0) continue;
      at = mmap(reinterpret_cast<void*>(kPreferredBase), size, PROT_READ | PROT_WRITE, MAP_SHARED | MAP_FIXED_NOREPLACE, fd, 0);
      if (at == MAP_FAILED) at = mmap(nullptr, size, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
      if (at != MAP_FAILED) break;
    }
    if (at == MAP_FAILED) {
      close(fd);
      throw std::runtime_error(fmt::format("shared particle memory: cannot map the arena: {}", std::strerror(errno)));
    }
    region_ = {fd, reinterpret_cast<std::uintptr_t>(at), size};
    free_[0] = size;
  }

  const SharedParticleMemory& region() const { return region_; }

  void* allocate(std::size_t bytes) {
    const std::size_t want = std::max<std::size_t>(1, (bytes + kPage - 1) / kPage) * kPage;
    std::lock_guard lock(mutex_);
    for (auto it = free_.begin(); it != free_.end(); ++it) {
      if (it->second < want) continue;
      const std::size_t offset = it->first, left = it->second - want;
      free_.erase(it);
      if (left > 0) free_[offset + want] = left;
      in_use_ += want;
      return reinterpret_cast<void*>(region_.base + offset);
    }
    throw std::bad_alloc();
  }

  void free(void* p, std::size_t bytes) noexcept {
    const std::size_t size = std::max<std::size_t>(1, (bytes + kPage - 1) / kPage) * kPage;
    std::size_t offset = reinterpret_cast<std::uintptr_t>(p) - region_.base;
    // The pages go back to the system now; the range reads as zeros if it is ever reused.
    fallocate(region_.fd, FALLOC_FL_PUNCH_HOLE | FALLOC_FL_KEEP_SIZE, static_cast<off_t>(offset), static_cast<off_t>(size));
    std::lock_guard lock(mutex_);
    in_use_ -= size;
    std::size_t length = size;
    auto next = free_.lower_bound(offset);
    if (next != free_.end() && next->first == offset + length) {
      length += next->second;
      next = free_.erase(next);
    }
    if (next != free_.begin()) {
      auto before = std::prev(next);
      if (before->first + before->second == offset) {
        offset = before->first;
        length += before->second;
        free_.erase(before);
      }
    }
    free_[offset] = length;
  }

  std::size_t in_use() const {
    std::lock_guard lock(mutex_);
    return in_use_;
  }

 private:
  SharedParticleMemory region_;
  mutable std::mutex mutex_;
  std::map<std::size_t, std::size_t> free_;  // offset -> length
  std::size_t in_use_ = 0;
};

std::atomic<Arena*> g_arena{nullptr};
std::mutex g_create;

}  // namespace

const SharedParticleMemory& share_particle_memory() {
  std::lock_guard lock(g_create);
  if (Arena* a = g_arena.load()) return a->region();
  auto* a = new Arena();  // lives as long as the process (arrays may be freed at exit)
  g_arena.store(a);
  return a->region();
}

const SharedParticleMemory* shared_particle_memory() {
  Arena* a = g_arena.load();
  return a ? &a->region() : nullptr;
}

std::size_t shared_particle_bytes_in_use() {
  Arena* a = g_arena.load();
  return a ? a->in_use() : 0;
}

namespace detail {

void* allocate_particle_bytes(std::size_t bytes) {
  if (Arena* a = g_arena.load()) return a->allocate(bytes);
  return ::operator new(bytes);
}

void free_particle_bytes(void* p, std::size_t bytes) noexcept {
  if (!p) return;
  Arena* a = g_arena.load();
  if (a && a->region().contains(p)) a->free(p, bytes);
  else ::operator delete(p);
}

}  // namespace detail

}  // namespace spate
