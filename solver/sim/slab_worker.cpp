#include "slab_worker.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <numeric>
#include <utility>
#include <sstream>

#include "../backend/cpu/cpu_backend.hpp"
#include "../domain/particle_checks.hpp"

namespace spate {

namespace {
// The worker times its own work (not the waits) for the balancer and device_busy_seconds.
using Clock = std::chrono::steady_clock;
double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }
}  // namespace

SlabWorker::SlabWorker(const Lattice& lattice, const PhysicsParams& params, SlabTransport& transport)
    : lattice_(lattice), params_(params), transport_(transport), particles_(lattice.dim),
      kernels_(std::make_unique<cpu::Kernels>(particles_, grid_)) {}

SlabWorker::~SlabWorker() = default;

void SlabWorker::take_share(const ParticleStore& global, const SlabLayout& layout) {
  layout_ = layout;
  const int s = transport_.slab();
  std::vector<std::uint32_t> mine;
  for (std::size_t i = 0; i < global.owned(); ++i)
    if (layout.owner_of(lattice_.cell_of(global.pos[0][i], 0)) == s) mine.push_back(static_cast<std::uint32_t>(i));
  // Copied field by field, without a packed buffer in between: every slab does this at once while
  // the whole generated set is still alive, so an extra copy would be a full set more at the peak.
  particles_ = ParticleStore(lattice_.dim);
  particles_.resize(mine.size());
  // Matched by registry entry and component, not by position: a store made under other
  // OptionalFields (relax_particles' worker carries `shift`, the generated set may not) lists other
  // fields; a field the global set lacks stays zero here.
  auto from = const_cast<ParticleStore&>(global).fields();
  auto to = particles_.fields();
  for (const FieldRef& field : to) {
    const auto source = std::find_if(from.begin(), from.end(),
                                     [&](const FieldRef& f) { return f.spec == field.spec && f.component == field.component; });
    if (source == from.end()) continue;
    const std::size_t size = field.elem_size;
    const char* src = source->bytes();
    char* dst = field.bytes();
    if (!src || !dst) continue;  // components beyond dim
    for (std::size_t i = 0; i < mine.size(); ++i) std::memcpy(dst + i * size, src + mine[i] * size, size);
  }
  particles_.set_owned(particles_.size());
  grid_.configure(lattice_, layout.faces[s], layout.faces[s + 1]);
  std::uint64_t id_bound = 0;
  for (const std::uint32_t id : global.id) id_bound = std::max<std::uint64_t>(id_bound, std::uint64_t{id} + 1);
  arrays().set_id_bound(static_cast<std::uint32_t>(std::min<std::uint64_t>(id_bound, 0xffffffffu)));
  arrays().upload(particles_);  // nothing to copy on the CPU backend: its arrays are this store
  host_stale_ = false;
}

void SlabWorker::sync_host() {
  if (!host_stale_) return;
  arrays().download(particles_, grid_);
  host_stale_ = false;
}

void SlabWorker::rebuild() {
  const double sorting = topology_.sort_seconds();
  timed(Pass::Rebuild, [&] { (faces_moved_ ? handovers_ : crossings_) += topology_.rebuild(arrays(), grid_, layout_, transport_); });
  faces_moved_ = false;
  host_stale_ = true;
  // The sorts: per-particle work in the same stretch as the loops (not the waits for the neighbours).
  const double seconds = topology_.sort_seconds() - sorting;
  busy_seconds_ += seconds;
  window_sort_seconds_ += seconds;
}

void SlabWorker::refresh_halo() {
  timed(Pass::HaloRefresh, [&] {
    topology_.begin_refresh(arrays());
    topology_.finish_refresh(arrays(), transport_);
  });
}

void SlabWorker::compute_rates() {
  if (params_.density_mode == DensityMode::Summation) {
    const auto t = Clock::now();
    timed(Pass::SummationDensity, [&] { kernels_->summation_density(particles_, grid_, params_); });
    window_fluid_seconds_ += since(t);
    refresh_halo();
  }
  const auto t0 = Clock::now();
  timed(Pass::EquationOfState, [&] { kernels_->equation_of_state(particles_, params_); });
  timed(Pass::WallState, [&] { kernels_->wall_state(particles_, grid_, params_); });
  // Surface tension: the colour gradient rides on the refresh below to the ghosts, whose normals
  // the force pass after the fluid rates reads (physics/surface_tension.hpp).
  // Antuono's diffusion: the same for the renormalised density gradient (density_gradient.hpp).
  const bool tension = params_.surface_tension.on;
  const bool antuono = uses_antuono_diffusion(params_);
  const bool heat = params_.heat.on;
  // Heat transfer: the temperatures behind the tank faces ride on the same refresh.
  if (heat) timed(Pass::WallTemperature, [&] { kernels_->wall_temperature(particles_, grid_, params_); });
  if (tension) timed(Pass::ColourGradient, [&] { kernels_->colour_gradient(particles_, grid_, params_); });
  if (antuono) timed(Pass::DensityGradient, [&] { kernels_->density_gradient(particles_, grid_, params_); });
  const double wall = since(t0);
  // The fluid phase excludes the wait for the halo (on a GPU: host time around the launches).
  double fluid = fluid_rates_overlapping_refresh();
  // SPS turbulence (physics/turbulence.hpp): the stress needs the walls' no-slip velocities, which
  // the ghosts have only from the refresh above, so it is computed after it and sent to the ghosts
  // by a refresh of its own before its divergence is added.
  if (params_.turbulence.on) {
    const auto t = Clock::now();
    timed(Pass::SpsStress, [&] { kernels_->sps_stress(particles_, grid_, params_); });
    fluid += since(t);
    refresh_halo();
    const auto t2 = Clock::now();
    timed(Pass::SpsAcceleration, [&] { kernels_->sps_acceleration(particles_, grid_, params_); });
    fluid += since(t2);
  }
  const auto t1 = Clock::now();
  if (tension) timed(Pass::SurfaceTension, [&] { kernels_->surface_tension(particles_, grid_, params_); });
  if (antuono) timed(Pass::AntuonoDiffusion, [&] { kernels_->antuono_diffusion(particles_, grid_, params_); });
  if (heat) timed(Pass::HeatRates, [&] { kernels_->heat_rates(particles_, grid_, params_); });
  fluid += since(t1);
  busy_seconds_ += wall + fluid;
  window_wall_seconds_ += wall;
  window_fluid_seconds_ += fluid;
}

// The paper's interior/boundary division: the owners' refreshed values are staged, the interior
// (owned particles that see no ghost) is computed before the slab waits for its neighbours'
// refresh, the boundary after. On a GPU the interior kernel is queued before the exchange blocks
// the host, so it runs during the copies; on the CPU the wait comes after the interior, so slabs
// only need to agree on wall + fluid time, not on each phase. Each particle's rates depend only
// on its own neighbour loop, so the split changes no result. Returns the seconds spent computing.
double SlabWorker::fluid_rates_overlapping_refresh() {
  SlabArrays& a = arrays();
  const auto t0 = Clock::now();
  topology_.begin_refresh(a);
  timed(Pass::FluidRates, [&] { kernels_->fluid_rates_range(grid_, params_, topology_.split().interior); });
  double seconds = since(t0);
  timed(Pass::HaloRefresh, [&] { topology_.finish_refresh(a, transport_); });
  const auto t1 = Clock::now();
  timed(Pass::FluidRates, [&] {
    kernels_->fluid_rates_range(grid_, params_, topology_.split().before);
    kernels_->fluid_rates_range(grid_, params_, topology_.split().after);
  });
  return seconds + since(t1);
}

// Particle shifting (physics/shifting.hpp), when the case asks for it: the displacements from the
// state the rates were computed on (ghosts included, still current), applied by correct(). Volume
// consistent: the ghosts' shifts by a halo refresh, then each density's change under them (the
// refresh's wait is not busy time, as in compute_rates).
void SlabWorker::shift(float dt) {
  if (!params_.shifting.enabled) return;
  auto t = Clock::now();
  timed(Pass::Shifting, [&] { kernels_->shifting(particles_, grid_, params_, dt); });
  double seconds = since(t);
  if (params_.shifting.volume_consistent) {
    refresh_halo();
    t = Clock::now();
    timed(Pass::Shifting, [&] { kernels_->shift_density(particles_, grid_, params_); });
    seconds += since(t);
  }
  busy_seconds_ += seconds;
  window_fluid_seconds_ += seconds;
}

void SlabWorker::prepare(bool rates) {
  // The pass times are the steps' (bench divides them by its steps), not the start's.
  const bool timing = std::exchange(pass_timers_, false);
  rebuild();
  if (rates) {
    compute_rates();
  } else {
    // The wall state and pressures still have to exist for outputs and probes.
    kernels_->equation_of_state(particles_, params_);
    kernels_->wall_state(particles_, grid_, params_);
    refresh_halo();
  }
  pass_timers_ = timing;
}

void SlabWorker::relax_step(float dt) {
  rebuild();
  kernels_->shifting(particles_, grid_, params_, dt);
  sync_host();
  for (std::size_t i = 0; i < particles_.owned(); ++i) {
    if (!params_.is_fluid(particles_.material[i])) continue;
    for (int a = 0; a < lattice_.dim; ++a) {
      particles_.pos[a][i] += particles_.shift[a][i];
      wrap_periodic(lattice_, particles_.pos[a][i], a);
    }
  }
}

void SlabWorker::refresh_ghosts() {
  refresh_halo();
  host_stale_ = true;  // the arrays' ghosts changed; a device backend's host mirror follows on demand
}

void SlabWorker::prepare_saved() { rebuild(); }

// The host's description of the position fault of the lowest faulty id (the arrays' reduction
// found it with the same predicates; positions on periodic axes are wrapped already).
std::optional<ParticleFault> SlabWorker::position_fault_message(std::uint32_t id) {
  if (id == SlabArrays::kNoFault) return std::nullopt;
  sync_host();
  std::optional<ParticleFault> fault;
  for (int a = 0; a < lattice_.dim; ++a) {
    const float* x = particles_.pos[a].data();
    const float lo = lattice_.origin[a], hi = lattice_.upper(a);
    for (std::size_t i = 0; i < particles_.owned(); ++i) {
      // A NaN or infinite position is reported as such (and never converted to a cell index).
      const PositionFault f = position_fault(lattice_, x[i], a);
      if (f != PositionFault::None && (!fault || particles_.id[i] < fault->id)) {
        std::ostringstream s;
        if (f == PositionFault::NonFinite) s << "has a non-finite position along " << "xyz"[a] << " (" << x[i] << ")";
        else s << "left the domain along " << "xyz"[a] << " (position " << x[i] << " m, domain [" << lo << ", " << hi << "] m)";
        fault = ParticleFault{particles_.id[i], s.str()};
      }
    }
  }
  if (fault && fault->id == id) return fault;
  return ParticleFault{id, "left the domain"};
}

// Nothing comes back to the host but the lowest faulty id (and, on a fault, the particles, so that
// the message is the host's). Between steps the arrays hold the owned particles' whole state.
std::optional<ParticleFault> SlabWorker::step(float dt) {
  SlabArrays& a = arrays();
  timed(Pass::Predict, [&] { kernels_->predict(particles_, params_, dt); });
  host_stale_ = true;
  removed_ = a.remove_escaped(open_);
  const std::uint32_t bad = a.wrap_and_find_position_fault(lattice_);
  if (auto fault = first_fault(transport_, position_fault_message(bad))) return fault;
  rebuild();
  compute_rates();
  shift(dt);
  timed(Pass::Correct, [&] { kernels_->correct(particles_, params_, dt); });
  return std::nullopt;
}

std::optional<ParticleFault> SlabWorker::health(float min_ratio, float max_ratio) {
  const std::uint32_t bad = arrays().find_unhealthy(HealthLimits(params_.materials, min_ratio, max_ratio));
  if (bad == SlabArrays::kNoFault) return std::nullopt;
  sync_host();  // the host check below writes the message for the same particle
  std::optional<ParticleFault> fault;
  const auto& p = particles_;
  const HealthLimits limits(params_.materials, min_ratio, max_ratio);
  for (std::size_t i = 0; i < p.owned(); ++i) {
    if (!limits.checked(p.material[i])) continue;
    if (fault && p.id[i] >= fault->id) continue;
    float x[3] = {0, 0, 0}, v[3] = {0, 0, 0};
    for (int a = 0; a < lattice_.dim; ++a) x[a] = p.pos[a][i], v[a] = p.vel[a][i];
    const bool finite = state_finite(lattice_.dim, x, v, p.density[i]);
    if (healthy(limits, finite, p.density[i], p.material[i])) continue;
    // Only a faulty particle pays for building its message.
    std::ostringstream s;
    if (!finite) {
      s << "has a non-finite position, velocity or density";
    } else {
      const float rho0 = params_.materials.of(p.material[i]).rho0;
      s << "has density " << p.density[i] << " kg/m3, outside [" << min_ratio * rho0 << ", " << max_ratio * rho0
        << "] (density.min_ratio/max_ratio)";
    }
    fault = ParticleFault{p.id[i], s.str()};
  }
  return fault;
}

float SlabWorker::local_time_step(const TimeStepControl& c) const {
  float dt = 0.0f;
  timed(Pass::TimeStep, [&] { dt = kernels_->min_time_step(particles_, params_, c); });
  return dt;
}

PassSeconds SlabWorker::pass_seconds() const { return pass_timers_ ? kernels_->pass_seconds() : PassSeconds{}; }

std::vector<std::int64_t> SlabWorker::slab_particle_counts() {
  std::vector<std::int64_t> counts(transport_.slab_count(), 0);
  counts[transport_.slab()] = static_cast<std::int64_t>(arrays().owned());
  transport_.sum(counts);
  return counts;
}

PhaseCosts column_costs(const ParticleStore& p, const Lattice& lattice, const MaterialTable& materials) {
  // Cost, not count: a fluid particle sums over all its neighbours with the full pair terms, a wall
  // particle only looks for fluid around it. A profile of the column case (perf: fluid loop 58%,
  // wall loop 18% of the time with 25k fluid and 51k wall particles) puts a fluid particle at about
  // 7 walls. The two weights land in the two phases the slabs synchronise between. Integer weights
  // keep the histogram sums exact.
  constexpr std::int64_t kFluidCost = 7, kWallCost = 1;
  PhaseCosts c{std::vector<std::int64_t>(lattice.cells[0], 0), std::vector<std::int64_t>(lattice.cells[0], 0)};
  for (std::size_t i = 0; i < p.owned(); ++i) {
    const int column = lattice.cell_of(p.pos[0][i], 0);
    if (materials.is_fluid(p.material[i])) c.fluid[column] += kFluidCost;
    else c.wall[column] += kWallCost;
  }
  return c;
}

PhaseCosts measured_column_costs(const ParticleStore& p, const Lattice& lattice, const MaterialTable& materials,
                                 double wall_seconds, double fluid_seconds, double sort_seconds) {
  const int columns = lattice.cells[0];
  std::vector<std::int64_t> fluid_count(columns, 0), wall_count(columns, 0);
  std::int64_t fluids = 0, walls = 0;
  for (std::size_t i = 0; i < p.owned(); ++i) {
    const bool fluid = materials.is_fluid(p.material[i]);
    ++(fluid ? fluid_count : wall_count)[lattice.cell_of(p.pos[0][i], 0)];
    ++(fluid ? fluids : walls);
  }
  if (fluids == 0) wall_seconds += std::exchange(fluid_seconds, 0.0);
  if (walls == 0) fluid_seconds += std::exchange(wall_seconds, 0.0);
  // The sort costs the same for every particle: each kind's phase gets its share.
  const double per_particle = fluids + walls ? 1e9 * sort_seconds / static_cast<double>(fluids + walls) : 0.0;
  const double per_wall = walls ? 1e9 * wall_seconds / static_cast<double>(walls) + per_particle : 0.0;
  const double per_fluid = fluids ? 1e9 * fluid_seconds / static_cast<double>(fluids) + per_particle : 0.0;
  // The wall phase also runs the equation of state over the fluid, but wall_state dominates it.
  PhaseCosts c{std::vector<std::int64_t>(columns, 0), std::vector<std::int64_t>(columns, 0)};
  for (int k = 0; k < columns; ++k) {
    c.wall[k] = std::llround(per_wall * static_cast<double>(wall_count[k]));
    c.fluid[k] = std::llround(per_fluid * static_cast<double>(fluid_count[k]));
  }
  return c;
}

double SlabWorker::rebalance(int min_columns) {
  sync_host();  // device backends: the owned positions and kinds for the cost histogram
  // One exact integer sum of both phase histograms: every slab ends up with the same numbers and
  // therefore the same faces, although the timings themselves differ from run to run. Faces do not
  // change the physics (neighbour order is (cell, id)), so results stay bit-identical.
  const int columns = lattice_.cells[0];
  PhaseCosts mine = measured_column_costs(particles_, lattice_, params_.materials, window_wall_seconds_, window_fluid_seconds_,
                                          window_sort_seconds_);
  window_wall_seconds_ = window_fluid_seconds_ = window_sort_seconds_ = 0.0;
  std::vector<std::int64_t> both(mine.wall);
  both.insert(both.end(), mine.fluid.begin(), mine.fluid.end());
  transport_.sum(both);
  PhaseCosts costs{std::vector<std::int64_t>(both.begin(), both.begin() + columns), std::vector<std::int64_t>(both.begin() + columns, both.end())};
  if (std::accumulate(both.begin(), both.end(), std::int64_t{0}) <= 0) {
    // Nothing timed (no step since the last pass): the estimated cost.
    costs = column_costs(particles_, lattice_, params_.materials);
    transport_.sum(costs.wall);
    transport_.sum(costs.fluid);
  }
  const double before = phase_imbalance(layout_, costs);
  const SlabLayout next = balanced_layout(costs, layout_.slabs(), min_columns);
  // Timings are noisy: faces move only for a gain of at least 2 % of the critical path, so they do
  // not jitter (each move hands particles over).
  const std::int64_t now_path = critical_path(layout_, costs), next_path = critical_path(next, costs);
  if (next != layout_ && static_cast<double>(next_path) < 0.98 * static_cast<double>(now_path)) {
    layout_ = next;
    faces_moved_ = true;
    ++face_moves_;
    const int s = transport_.slab();
    grid_.configure(lattice_, layout_.faces[s], layout_.faces[s + 1]);
    // The next rebuild() migrates particles to their new owners.
  }
  return before;
}

std::size_t SlabWorker::allocated_bytes() const {
  return particles_.size() * particles_.bytes_per_particle() + grid_.bytes() + kernels_->device_bytes();
}

std::optional<ParticleFault> first_fault(SlabTransport& t, const std::optional<ParticleFault>& mine) {
  const double lowest = t.min(mine ? static_cast<double>(mine->id) : INFINITY);
  if (!std::isfinite(lowest)) return std::nullopt;
  // The slab that holds the lowest id shares its description.
  Bytes text;
  if (mine && static_cast<double>(mine->id) == lowest) text.assign(mine->what.begin(), mine->what.end());
  for (auto& b : t.allgather(text))
    if (!b.empty()) return ParticleFault{static_cast<std::uint32_t>(lowest), std::string(b.begin(), b.end())};
  return ParticleFault{static_cast<std::uint32_t>(lowest), "is faulty"};
}

}  // namespace spate
