#pragma once
// OpenMP regions cost a fork and a barrier each; when the machine is oversubscribed (tests running
// side by side, other jobs) a barrier can cost a whole scheduler slice. Loops with little work per
// element therefore go parallel only above kCheapGrain elements, pair loops above kPairGrain.
#include <cstdint>

namespace spate::cpu {
constexpr std::int64_t kCheapGrain = 50000;
constexpr std::int64_t kPairGrain = 20000;
}  // namespace spate::cpu
