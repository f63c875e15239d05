#include "interaction_count.hpp"

#include "parallel.hpp"

#include "../../particles/particle_access.hpp"
#include "../../physics/dispatch.hpp"

namespace spate::cpu {

InteractionCounts count_interactions(const ParticleStore& p, const CellGrid& grid, const PhysicsParams& P) {
  std::int64_t fluid = 0, wall = 0;
  dispatch_kernel_dim(P, [&]<class Kernel, int Dim>() {
    const CellGridView v = grid.view();
    const auto cells = static_cast<std::int64_t>(grid.owned_cell_count());
    // Integer sums: exact in any order.
#pragma omp parallel for schedule(dynamic, 64) reduction(+ : fluid, wall)
    for (std::int64_t c = 0; c < cells; ++c) {
      int g[3];
      grid.global_coords(static_cast<std::uint32_t>(c), g);
      for (std::uint32_t i = v.start[c]; i < v.start[c + 1]; ++i) {
        const bool i_fluid = P.is_fluid(p.material[i]);
        const Vec<Dim> xi = load_vec<Dim>(p.pos, i);
        std::int64_t inside = 0;
        v.for_each_neighbour_range(g, [&](std::uint32_t b, std::uint32_t e) {
          for (std::uint32_t j = b; j < e; ++j)
            inside += j != i && (i_fluid || P.is_fluid(p.material[j])) && distance_squared<Dim>(xi, p.pos, j) < P.support2;
        });
        (i_fluid ? fluid : wall) += inside;
      }
    }
  });
  InteractionCounts n;
  n.fluid = fluid;
  n.wall = wall;
  // The summation pass visits exactly the pairs of the fluid-rate pass (fluid i, any j).
  n.summation = P.density_mode == DensityMode::Summation ? fluid : 0;
  return n;
}

}  // namespace spate::cpu
