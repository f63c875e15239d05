#pragma once
// Neighbour interactions of one step, for throughput figures (`spate bench`): the pairs (i, j),
// j != i, inside the kernel support that the step's neighbour passes evaluate. The self term
// (j = i, which the loops also visit and which adds exactly zero to the rates) is not counted.
#include <cstdint>

#include "../../grid/cell_grid.hpp"
#include "../../particles/particle_store.hpp"
#include "../../physics/params.hpp"

namespace spate::cpu {

struct InteractionCounts {
  std::int64_t fluid = 0;      // fluid rates: owned fluid i with every particle j (fluid or wall)
  std::int64_t wall = 0;       // Adami wall state: owned wall i with every fluid j
  std::int64_t summation = 0;  // mass summation density (0 unless density.mode = summation): fluid i, any j
  std::int64_t total() const { return fluid + wall + summation; }
};

// Counts over the owned particles of a sorted, halo-complete grid (the state after prepare()).
InteractionCounts count_interactions(const ParticleStore& p, const CellGrid& g, const PhysicsParams& P);

}  // namespace spate::cpu
