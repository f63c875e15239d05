#pragma once
// One device's share of the simulation: its slab of owned particles, their ghosts, the cell grid
// and the step pieces in the order the design prescribes. The backend (StepKernels) holds the
// particles and does the arithmetic; the worker sequences it, runs the step topology on the
// backend's arrays (SlabTopology) and talks to the neighbours through the transport.
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "../backend/step_kernels.hpp"
#include "../comm/transport.hpp"
#include "../domain/slab_layout.hpp"
#include "../domain/slab_topology.hpp"
#include "../grid/cell_grid.hpp"
#include "../particles/particle_store.hpp"
#include "../physics/params.hpp"
#include "../physics/timestep.hpp"

namespace spate {

// What went wrong with a particle, for the instability diagnosis.
struct ParticleFault {
  std::uint32_t id = 0xffffffffu;
  std::string what;
};

class SlabWorker {
 public:
  SlabWorker(const Lattice& lattice, const PhysicsParams& params, SlabTransport& transport);
  ~SlabWorker();
  // The physics loops (default: the CPU backend). Set before take_share().
  void use_kernels(std::unique_ptr<StepKernels> kernels) { kernels_ = std::move(kernels); }

  // Takes the particles of `global` that lie in this slab's columns.
  void take_share(const ParticleStore& global, const SlabLayout& layout);
  // Sort, halos and everything the rates need; with `rates` also the accelerations and density
  // rates (a fresh start; a restart brings them from the checkpoint).
  void prepare(bool rates);
  // Ghosts take their owners' current Refresh fields (velocity, density, pressure). Between steps
  // the ghosts still hold the values of the step's force evaluation (the predicted velocity and
  // density), the owners the corrected ones: what reads ghosts between steps (probes) refreshes
  // them first, so that it sees the same values whatever the split. Collective.
  void refresh_ghosts();
  // Sort and halos only, for particles read back from a snapshot or checkpoint: they keep the
  // pressures and wall states they were saved with, so probes sample them exactly as the run did.
  void prepare_saved();
  // One full step of size dt. Fluid that left through an open side (set_open_sides) is removed
  // first (removed_ids()); returns a fault if a particle left the domain otherwise (before rates).
  std::optional<ParticleFault> step(float dt);
  // One iteration of the relaxation before t = 0 (sim/relax.hpp): sort and halos, then every owned
  // fluid particle moves by its particle-shifting displacement for `dt` (params' shifting scale).
  void relax_step(float dt);
  // Where fluid may leave the domain for good (default: nowhere; every exit is a fault).
  void set_open_sides(const OpenSides& open) { open_ = open; }
  // The ids this slab removed in the last step, increasing.
  const std::vector<std::uint32_t>& removed_ids() const { return removed_; }
  // NaN/infinity or density outside [min, max] x rho0 among owned particles.
  std::optional<ParticleFault> health(float min_ratio, float max_ratio);
  float local_time_step(const TimeStepControl& c) const;

  // Moves faces to shorten the step's critical path, from the time each slab measured in its wall
  // and fluid loops since the previous pass (collective; every slab takes the same decision). Falls
  // back to the estimated cost (fluid 7, wall 1 per particle) when nothing was timed. Returns the
  // phase imbalance (phase_imbalance in slab_layout.hpp) before the move.
  double rebalance(int min_columns);
  std::vector<std::int64_t> slab_particle_counts();  // collective
  // Traffic across faces so far, totals over all slabs (the same on every slab): particles that
  // crossed a face by moving, particles handed over because faces moved (the migration right after
  // a balancing pass that moved faces), and the balancing passes that moved faces.
  std::int64_t crossings() const { return crossings_; }
  std::int64_t handovers() const { return handovers_; }
  std::int64_t face_moves() const { return face_moves_; }

  void set_params(const PhysicsParams& p) { params_ = p; }
  const PhysicsParams& params() const { return params_; }
  // The host store and grid. With a device backend they are a mirror, brought up to date here when
  // a step changed the device copy (output steps: probes, snapshots, checkpoints, in situ); with
  // the CPU backend they are its arrays.
  ParticleStore& particles() {
    sync_host();
    return particles_;
  }
  const CellGrid& grid() {
    sync_host();
    return grid_;
  }
  const Lattice& lattice() const { return lattice_; }
  SlabTransport& transport() { return transport_; }
  const SlabLayout& layout() const { return layout_; }
  std::size_t allocated_bytes() const;
  // Wall-clock seconds this slab spent in its neighbour loops and its sort (not waiting for others).
  double busy_seconds() const { return busy_seconds_; }
  // Seconds per pass of this slab's steps so far (backend/pass_times.hpp): zeros unless
  // SPATE_PASS_TIMERS=1. On a device, waits for the passes it timed.
  PassSeconds pass_seconds() const;

 private:
  // `body` (a pass, or the topology's part of the step), timed as pass p when the timers are on.
  template <class Body>
  void timed(Pass p, Body&& body) const {
    if (!pass_timers_) {
      body();
      return;
    }
    kernels_->begin_pass(p);
    body();
    kernels_->end_pass(p);
  }

  void rebuild();        // migrate, sort, halos
  void compute_rates();  // EOS, walls, fluid rates
  void shift(float dt);  // particle shifting, when enabled (before the corrector applies it)
  void refresh_halo();   // the ghosts' Refresh fields
  SlabArrays& arrays() const { return kernels_->arrays(); }
  void sync_host();
  double fluid_rates_overlapping_refresh();
  std::optional<ParticleFault> position_fault_message(std::uint32_t id);

  Lattice lattice_;
  PhysicsParams params_;
  SlabTransport& transport_;
  SlabLayout layout_;
  ParticleStore particles_;
  CellGrid grid_;
  SlabTopology topology_;
  bool host_stale_ = false;
  bool pass_timers_ = pass_timers_enabled();
  double busy_seconds_ = 0.0;
  // Loop seconds since the last balancing pass, per synchronised phase (see PhaseCosts).
  double window_wall_seconds_ = 0.0, window_fluid_seconds_ = 0.0, window_sort_seconds_ = 0.0;
  std::unique_ptr<StepKernels> kernels_;
  std::int64_t crossings_ = 0, handovers_ = 0, face_moves_ = 0;
  bool faces_moved_ = false;
  OpenSides open_;
  std::vector<std::uint32_t> removed_;
};

// Estimated work per x column of the owned particles (fluid 7 in the fluid phase, wall 1 in the wall
// phase, per particle): the first faces, before anything was timed.
PhaseCosts column_costs(const ParticleStore& p, const Lattice& lattice, const MaterialTable& materials);

// This slab's measured seconds spread over its x columns, in nanoseconds: the wall phase in
// proportion to the owned particles' wall-phase share, the fluid phase to the fluid particles (a
// slab without fluid charges both phases to its walls and vice versa). Summed over slabs it is
// the measured histogram the balancer evens out.
// `sort_seconds` (the owned sort and the ghosts' arrival) are spread evenly over all particles.
PhaseCosts measured_column_costs(const ParticleStore& p, const Lattice& lattice, const MaterialTable& materials,
                                 double wall_seconds, double fluid_seconds, double sort_seconds = 0.0);

// The fault with the lowest particle id over all slabs (collective), or none.
std::optional<ParticleFault> first_fault(SlabTransport& t, const std::optional<ParticleFault>& mine);

}  // namespace spate
