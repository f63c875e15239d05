#pragma once
// OpenMP regions cost a fork and a barrier each. On a machine whose cores this process has to
// itself that is a few microseconds, and a small 2D case runs 1.7x faster on 2 cores than on one;
// on an oversubscribed machine (runs or tests side by side) a barrier waits for a descheduled
// thread, a whole scheduler slice, and the same case ran 9x slower in parallel than serial
// (docs/performance.md, "Small cases and busy machines"). So loops with little work per element go
// parallel only above cheap_grain() elements, pair loops above pair_grain(): high (safe) while the
// machine is busy, low while it has cores to spare, as CoreWatch (core_watch.hpp) finds every
// second. Every loop under a grain writes per element or takes an exact minimum: the bits never
// depend on it.
#include <atomic>
#include <cstdint>
#include <optional>

namespace spate::cpu {

// The grains while other processes keep the cores busy, and while this one has them to itself.
constexpr std::int64_t kBusyCheapGrain = 50000;
constexpr std::int64_t kBusyPairGrain = 20000;
constexpr std::int64_t kFreeCheapGrain = 8000;
constexpr std::int64_t kFreePairGrain = 2000;

namespace detail {
inline std::atomic<bool> cores_free{false};  // starts safe
inline std::atomic<bool> fixed{false};       // set by fix_cores_free: CoreWatch leaves it alone
}

inline std::int64_t cheap_grain() { return detail::cores_free.load(std::memory_order_relaxed) ? kFreeCheapGrain : kBusyCheapGrain; }
inline std::int64_t pair_grain() { return detail::cores_free.load(std::memory_order_relaxed) ? kFreePairGrain : kBusyPairGrain; }
// CoreWatch's verdict: whether this process's threads have cores to themselves (ignored while fixed).
inline void set_cores_free(bool free) {
  if (!detail::fixed.load(std::memory_order_relaxed)) detail::cores_free.store(free, std::memory_order_relaxed);
}
inline bool cores_free() { return detail::cores_free.load(std::memory_order_relaxed); }
// For tests: one grain for every run of the process from now on (std::nullopt: measured again).
inline void fix_cores_free(std::optional<bool> free) {
  detail::fixed.store(false, std::memory_order_relaxed);
  if (free) set_cores_free(*free);
  detail::fixed.store(free.has_value(), std::memory_order_relaxed);
}

}  // namespace spate::cpu
