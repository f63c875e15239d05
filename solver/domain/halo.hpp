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
  // Sorts the owned particles (CellGrid::sort_owned), appends the ghosts and sorts them. In two
  // halves: send() picks the owned particles of the edge columns by a scan (no sort needed) and
  // exchanges them; receive() sorts the owned particles and takes the ghosts in. The sort thus
  // runs after the slabs met, in the same stretch of work as the neighbour loops, which is where
  // the balancer evens out the time.
  void build(ParticleStore& p, CellGrid& grid, SlabTransport& transport) {
    send(p, grid, transport);
    receive(p, grid);
  }
  void send(ParticleStore& p, const CellGrid& grid, SlabTransport& transport);
  void receive(ParticleStore& p, CellGrid& grid);
  // Copies the FieldSet::Refresh fields of every ghost from its source again.
  void refresh(ParticleStore& p, SlabTransport& transport) {
    begin_refresh(p, transport);
    finish_refresh(p, transport);
  }
  // The refresh in two halves, so that work which sees no halo ghost can run in between: the first
  // posts what the neighbours get (SlabTransport::post) and refreshes the periodic images of
  // owned columns; the second collects the neighbours' and refreshes the halo ghosts and their
  // images.
  void begin_refresh(ParticleStore& p, SlabTransport& transport);
  void finish_refresh(ParticleStore& p, SlabTransport& transport);

  std::size_t ghost_count() const { return ghosts_; }

 private:
  void make_periodic_images(ParticleStore& p, const CellGrid& grid, int axis);
  void refresh_images(ParticleStore& p, bool local);

  std::vector<std::uint32_t> send_left_, send_right_;  // owned indices sent each way
  // Slots (absolute indices) that the particles received from the left/right landed in.
  std::vector<std::uint32_t> slots_left_, slots_right_;
  // Periodic images: copy source -> target (absolute indices after the ghost sort), in creation order.
  // An image is local when its source lies in an owned column (images keep their source's x).
  std::vector<std::uint32_t> image_source_, image_target_;
  std::vector<std::uint8_t> image_local_;
  Bytes from_left_, from_right_;        // received by send(), taken in by receive()
  std::size_t ghosts_ = 0;
};

// Sends owned particles whose x column left this slab to the slab that owns it now, repeating
// neighbour hops until every particle is home (several hops only after faces moved). Ghosts are
// dropped. Returns the number of particles that moved, summed over all slabs.
std::int64_t migrate(ParticleStore& p, const std::vector<int>& faces, const Lattice& lattice,
                     SlabTransport& transport);

}  // namespace spate
