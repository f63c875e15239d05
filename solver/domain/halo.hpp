#pragma once
// Ghost particles of one slab: copies of the neighbours' particles in the x columns next to each face
// (one kernel support wide, since a cell is at least one support), and periodic images along y/z.
// The plan remembers where each ghost came from, so that fields which change later in the step
// (wall pressure, summation density) can be refreshed without rebuilding.
#include <cstdint>
#include <vector>

#include "../comm/transport.hpp"
#include "../grid/cell_grid.hpp"
#include "../particles/particle_pack.hpp"

namespace spate {

class Halo {
 public:
  // Owned particles must be sorted (CellGrid::sort_owned); appends ghosts, then sorts them.
  void build(ParticleStore& p, CellGrid& grid, SlabTransport& transport);
  // Copies the FieldSet::Refresh fields of every ghost from its source again.
  void refresh(ParticleStore& p, SlabTransport& transport);

  std::size_t ghost_count() const { return ghosts_; }

 private:
  void make_periodic_images(ParticleStore& p, const CellGrid& grid, int axis);

  std::vector<std::uint32_t> send_left_, send_right_;  // owned indices sent each way
  // Slots (absolute indices) that the particles received from the left/right landed in.
  std::vector<std::uint32_t> slots_left_, slots_right_;
  // Periodic images: copy source -> target (absolute indices after the ghost sort), in creation order.
  std::vector<std::uint32_t> image_source_, image_target_;
  std::size_t ghosts_ = 0;
};

// Sends owned particles whose x column left this slab to the slab that owns it now, repeating
// neighbour hops until every particle is home (several hops only after faces moved). Ghosts are
// dropped. Returns the number of particles that moved, summed over all slabs.
std::int64_t migrate(ParticleStore& p, const std::vector<int>& faces, const Lattice& lattice,
                     SlabTransport& transport);

}  // namespace spate
