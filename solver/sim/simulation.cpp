#include "simulation.hpp"

#include <omp.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <mutex>
#include <numeric>
#include <optional>
#include <fstream>
#include <thread>

#include <pthread.h>
#include <sched.h>

#include "../backend/cpu/core_watch.hpp"
#include "../backend/cuda/device_plan.hpp"
#include "../backend/cuda/device_runtime.hpp"
#include "../comm/in_process_transport.hpp"
#include "../comm/process_group.hpp"
#ifdef SPATE_WITH_MPI
#include "../comm/mpi_transport.hpp"
#endif
#include "../io/checkpoint.hpp"
#include "../io/output_file.hpp"
#include "memory_estimate.hpp"
#include "../io/vtk_snapshot.hpp"
#include "../particles/particle_pack.hpp"
#include "closed_volume.hpp"
#include "flow_drive.hpp"
#include "probes.hpp"
#include "relax.hpp"
#include "slab_worker.hpp"

namespace spate {

namespace {

using Clock = std::chrono::steady_clock;

constexpr int kMinColumnsPerSlab = 3;
// Balancing passes (balance_every > 0): every balance_every steps, and before the first of those
// after 2, 4, 8, ... steps of the run. The first faces follow an estimated cost; these calibration
// passes replace it with the slabs' measured times, each over twice the steps of the one before,
// so that the faces settle within a few steps, then follow the flow without chasing noise.
bool balancing_pass_due(std::int64_t taken, std::int64_t step, std::int64_t every) {
  if (every <= 0 || taken <= 0) return false;
  if (step % every == 0) return true;
  return taken < every && taken >= 2 && (taken & (taken - 1)) == 0;
}

std::string step_name(std::int64_t step) { return fmt::format("step_{:08d}", step); }

// geometry/solid_<material>.vtp and, for moving solids, solid_<material>_start.vtp; a shaped tank's
// geometry/tank.vtp (and tank_start.vtp when it moves) (Simulation::run
// says what for). `initial`: the particles at t = 0, or null on a restart, when they are generated
// again if some solid moves (its particles' start is what the pipeline fits to).
void write_solid_geometry(const Case& c, const std::filesystem::path& out, const ParticleStore* initial) {
  const MaterialTable M = physics_params(c).materials;
  std::optional<ParticleStore> generated;
  const std::filesystem::path folder = out / "geometry";
  // The start positions and ids of a moving body's particles, <name>_start.vtp.
  auto write_start = [&](const std::string& name, int material) {
    if (!initial) initial = &generated.emplace(generate_particles(c));
    std::vector<std::array<double, 3>> points;
    std::vector<std::uint32_t> ids;
    for (std::size_t i = 0; i < initial->size(); ++i) {
      if (initial->material[i] != material) continue;
      points.push_back({initial->pos[0][i], initial->pos[1][i], c.dim == 3 ? initial->pos[2][i] : 0.0f});
      ids.push_back(initial->id[i]);
    }
    write_file_atomically(folder / (name + "_start.vtp"), points_vtp(points, ids));
  };
  if (c.tank_shape) {  // a shaped tank's surface: the pipeline draws the vessel (where it is, if it moves)
    create_output_folder(folder);
    write_file_atomically(folder / "tank.vtp", surface_vtp(*c.tank_shape));
    if (c.tank_motion >= 0) write_start("tank", M.tank());
  }
  for (std::size_t k = 0; k < c.solids.size(); ++k) {
    const SolidSpec& solid = c.solids[k];
    const bool moves = solid.motion >= 0;
    if (!solid.shape && !(moves && c.dim == 3)) continue;
    const int material = M.solid(static_cast<int>(k));
    create_output_folder(folder);
    write_file_atomically(folder / fmt::format("solid_{}.vtp", material),
                          solid.shape ? surface_vtp(*solid.shape) : box_surface_vtp(solid.box.min, solid.box.max));
    if (moves) write_start(fmt::format("solid_{}", material), material);
  }
}

// The first time after `time` on the grid k * interval (k whole), in closed form: a loop adding the
// interval would never get past `time` when the interval is below its resolution. Such an interval
// (or one shorter than the time step) means every step.
double next_on_grid(double time, double interval) {
  const double next = (std::floor(time / interval + 1e-9) + 1) * interval;
  return std::isfinite(next) && next > time ? next : std::nextafter(time, INFINITY);
}

std::atomic<int> stop_signal{0};
constexpr std::size_t kRemovedIdsKept = 10;  // removed ids named in summary.json

// What every slab learns at the end of a step (one collective): the faulty particle with the
// lowest id, the fluid removed through open sides (ids, increasing) and the signal that asked for
// a stop (0: none; the largest number if several, so that every rank agrees).
struct StepReport {
  std::optional<ParticleFault> fault;
  std::vector<std::uint32_t> removed;
  int stop_signal = 0;
};

StepReport share_report(SlabTransport& t, const std::optional<ParticleFault>& fault, const std::vector<std::uint32_t>& removed,
                        int stop) {
  Bytes mine;
  auto put = [&](const void* data, std::size_t size) {
    const char* c = static_cast<const char*>(data);
    mine.insert(mine.end(), c, c + size);
  };
  const std::uint32_t id = fault ? fault->id : 0xffffffffu;
  const std::uint32_t text = fault ? static_cast<std::uint32_t>(fault->what.size()) : 0;
  const std::uint32_t count = static_cast<std::uint32_t>(removed.size());
  const std::uint8_t flags = fault ? 1 : 0;
  const std::int32_t signal = stop;
  put(&flags, 1);
  put(&signal, 4);
  put(&id, 4);
  put(&text, 4);
  if (fault) put(fault->what.data(), text);
  put(&count, 4);
  put(removed.data(), removed.size() * 4);
  StepReport r;
  for (const Bytes& b : t.allgather(mine)) {
    std::size_t at = 0;
    auto get = [&](void* out, std::size_t size) {
      if (at + size > b.size()) throw std::logic_error("step report: short message");
      std::memcpy(out, b.data() + at, size);
      at += size;
    };
    std::uint8_t f = 0;
    std::int32_t their_signal = 0;
    std::uint32_t their_id = 0, their_text = 0, their_count = 0;
    get(&f, 1);
    get(&their_signal, 4);
    get(&their_id, 4);
    get(&their_text, 4);
    std::string what(their_text, '\0');
    get(what.data(), their_text);
    get(&their_count, 4);
    const std::size_t first = r.removed.size();
    r.removed.resize(first + their_count);
    get(r.removed.data() + first, their_count * 4ul);
    r.stop_signal = std::max(r.stop_signal, static_cast<int>(their_signal));
    if ((f & 1) && (!r.fault || their_id < r.fault->id)) r.fault = ParticleFault{their_id, what};
  }
  std::sort(r.removed.begin(), r.removed.end());
  return r;
}

// Everything the worker threads of this process share. Written by the writer slab only.
struct Shared {
  Shared(const Case& case_in, const RunOptions& options) : c(case_in), opts(options), initial(case_in.dim) {}
  const Case& c;
  const RunOptions& opts;
  Lattice lattice;
  PhysicsParams params;
  ParticleStore initial;
  CheckpointMeta start;
  bool restarted = false;
  SlabLayout layout;
  int omp_threads = 1;
  int local_slabs = 1;
  RunResult result;
  std::mutex result_mutex;
  std::vector<SlabWorker*> workers;  // local slabs, for in-situ views
  int workers_first_slab = 0;        // global index of this process's first slab (rank * devices)
  std::vector<SteeringChange> steering_history;  // accepted so far (from the checkpoint, then live)
};

// Slab 0's list of changes, on every slab (collective).
std::vector<SteeringChange> share_changes(SlabTransport& t, const std::vector<SteeringChange>& mine) {
  std::string text;
  for (auto& c : mine) text += to_log_line(c) + "\n";
  const auto all = t.allgather(Bytes(text.begin(), text.end()));
  return parse_log(std::string(all[0].begin(), all[0].end()), "steering request");
}

std::string history_text(const std::vector<SteeringChange>& history) {
  std::string s;
  for (auto& c : history) s += to_log_line(c) + "\n";
  return s;
}

// Every particle where slab 0 (the writer) can read it, and the id order across slabs (collective;
// the other slabs get nothing back). Checkpoints are independent of the split because of this
// order. Slabs in the writer's process are read in place (they wait at the barrier after the write),
// so on one rank a checkpoint costs no particle copy at all; slabs of other ranks send their packed
// share to the writer, which unpacks it part by part, freeing each buffer once unpacked.
struct GatheredParticles {
  std::vector<ParticleStore*> slabs;   // owned particles [0, owned) of every global slab
  std::vector<ParticleStore> received; // the other ranks' slabs
  struct Entry {
    std::uint32_t id, slab, index;
  };
  std::vector<Entry> by_id;
};

GatheredParticles gather_to_writer(SlabWorker& w, const std::vector<SlabWorker*>& local, bool writer_process) {
  ParticleStore& p = w.particles();
  Bytes share;
  if (!writer_process) {
    std::vector<std::uint32_t> mine(p.owned());
    std::iota(mine.begin(), mine.end(), 0u);
    share = pack_particles(p, mine, FieldSet::All);
  }
  std::vector<Bytes> packed = w.transport().gather(std::move(share));
  GatheredParticles g;
  if (packed.empty()) return g;
  g.received.reserve(packed.size());
  for (std::size_t s = 0; s < packed.size(); ++s) {
    if (s < local.size()) {
      g.slabs.push_back(&local[s]->particles());
      continue;
    }
    g.received.emplace_back(p.dim());
    unpack_append(g.received.back(), packed[s], FieldSet::All);
    g.received.back().set_owned(g.received.back().size());
    g.slabs.push_back(&g.received.back());
    Bytes().swap(packed[s]);
  }
  std::size_t total = 0;
  for (auto* slab : g.slabs) total += slab->owned();
  g.by_id.reserve(total);
  for (std::uint32_t s = 0; s < g.slabs.size(); ++s)
    for (std::uint32_t i = 0; i < g.slabs[s]->owned(); ++i) g.by_id.push_back({g.slabs[s]->id[i], s, i});
  std::sort(g.by_id.begin(), g.by_id.end(), [](const auto& a, const auto& b) { return a.id < b.id; });
  return g;
}

// The progress line: on a terminal one line rewritten in place every second; otherwise (a log
// file) an info message every 5 s, timestamped by the log.
class Progress {
 public:
  Progress(bool enabled, std::int64_t particles)
      : enabled_(enabled && spdlog::should_log(spdlog::level::info)), particles_(particles), tty_(isatty(STDOUT_FILENO)) {}
  void update(std::int64_t steps, double time, double end_time, double start_time, std::int64_t removed = 0, bool force = false) {
    if (!enabled_) return;
    const auto now = Clock::now();
    const double since = std::chrono::duration<double>(now - last_).count();
    if (!force && since < (tty_ ? 1.0 : 5.0)) return;
    last_ = now;
    const double wall = std::chrono::duration<double>(now - begin_).count();
    const double sps = wall > 0 ? steps / wall : 0.0;
    const double done = (time - start_time) / std::max(1e-300, end_time - start_time);
    const double eta = done > 0 ? wall * (1 - done) / done : 0.0;
    std::string line = fmt::format("t = {:.5f} s  step {}  {:.2f} steps/s  {:.3g} particle-steps/s  ETA {:.0f} s", time, steps,
                                   sps, sps * particles_, eta);
    if (removed > 0) line += fmt::format("  removed {}", removed);
    if (tty_) {
      std::printf("\r%s   ", line.c_str());
      std::fflush(stdout);
      wrote_tty_ = true;
    } else {
      spdlog::info("{}", line);
    }
  }
  void finish() {
    if (enabled_ && wrote_tty_) std::printf("\n");
  }

 private:
  bool enabled_;
  std::int64_t particles_;
  bool tty_;
  bool wrote_tty_ = false;
  Clock::time_point begin_ = Clock::now();
  Clock::time_point last_ = Clock::now();
};

// The open sides of a moving tank at time t: the particles are taken back to where they were,
// relative to the tank, at t = 0 (particle_checks.hpp, OpenSides).
OpenSides tank_open_sides(OpenSides o, const MotionSet& motions, int motion, double t) {
  const MotionSpec& m = motions.spec(motion);
  MotionSample s = motions.sample(motion, t);
  o.moving = true;
  for (int a = 0; a < 3; ++a) o.centre[a] = static_cast<float>(m.centre[a]), o.shift[a] = static_cast<float>(s.displacement[a]);
  s.angle = -s.angle;  // the turn back
  for (int k = 0; k < 3; ++k) {
    Vec3 e{0, 0, 0};
    e[k] = 1.0;
    const Vec3 column = turned(m, s, e);
    for (int a = 0; a < 3; ++a) o.back[a][k] = static_cast<float>(column[a]);
  }
  return o;
}

class Worker {
 public:
  // One single-threaded worker per CPU of this process's affinity mask, when they fit: the kernel
  // then never puts two workers on one core while the other idles (they wait for each other every
  // step, so one descheduled worker stalls all).
  void pin_worker() {
    if (s_.omp_threads != 1 || s_.local_slabs < 2) return;
    cpu_set_t allowed;
    if (sched_getaffinity(0, sizeof allowed, &allowed) != 0) return;
    if (CPU_COUNT(&allowed) < s_.local_slabs) return;
    const int d = t_.slab() - s_.workers_first_slab;
    for (int cpu = 0, seen = 0; cpu < CPU_SETSIZE; ++cpu) {
      if (!CPU_ISSET(cpu, &allowed)) continue;
      if (seen++ != d) continue;
      cpu_set_t one;
      CPU_ZERO(&one);
      CPU_SET(cpu, &one);
      pthread_setaffinity_np(pthread_self(), sizeof one, &one);
      return;
    }
  }
  Worker(Shared& s, SlabTransport& t) : s_(s), t_(t), w_(s.lattice, s.params, t), open_sides_(open_sides(s.c)) {
    w_.set_open_sides(open_sides_);
  }

  void run() {
    omp_set_num_threads(s_.omp_threads);
    pin_worker();
    const bool writer = t_.slab() == 0;
    if (s_.opts.backend == "cuda") {
      const int worker = t_.slab() % s_.opts.devices;
      const int gpu = gpu::device_for_worker(worker, s_.opts.devices, gpu::node_local_rank(), gpu::device_count());
      w_.use_kernels(gpu::make_cuda_kernels(gpu, s_.lattice.dim));
    }
    // The first slab of each process reports the run's outcome to it (every rank needs the exit status).
    const bool reporter = t_.slab() == s_.workers_first_slab;
    w_.take_share(s_.initial, s_.layout);
    {
      std::lock_guard lock(s_.result_mutex);
      s_.workers[t_.slab() - s_.workers_first_slab] = &w_;
    }
    t_.barrier();  // every slab has its share: the generated set is no longer needed (on the
                   // paper's case it holds about a gigabyte)
    if (t_.slab() == s_.workers_first_slab) s_.initial = ParticleStore(s_.c.dim);
    t_.barrier();
    // The parameters as steered so far (a restart continues steered) and the walls' motion at the
    // start time, before the first rates.
    PhysicsParams params = s_.params;
    int insitu_every = 1;
    MotionSet motions(s_.c.motions, s_.c.dim);
    // The floating solids (rigid_bodies.hpp): a restart continues from their saved state and loads
    // (checked when the run was set up), with their springs as steered.
    RigidBodies bodies(s_.c, &motions);
    bodies_ = &bodies;
    SteeringTarget steer{&params, &insitu_every, &motions, &bodies};
    for (auto& change : s_.steering_history) {
      apply(change, steer);
      if (change.name == "insitu_every" && s_.opts.insitu) s_.opts.insitu->set_interval(insitu_every);
    }
    steer.checkpoint_now = steer.stop = false;
    if (s_.restarted) bodies.restore(s_.start.bodies);
    // A driven periodic flow (flow_drive.hpp): a restart continues with the saved body force.
    FlowDrive drive(s_.c);
    drive_ = &drive;
    if (s_.restarted) drive.restore(s_.start.drive);
    drive.apply(params);
    // A fluid that fills its container (closed_volume.hpp): its volume at the start, or the saved one.
    ClosedVolume volume(s_.c);
    volume_ = &volume;
    if (s_.restarted) volume.restore(s_.start.closed_volume);
    motions.set_step(params, s_.start.time, s_.start.time);
    bodies.set_step(params);
    w_.set_params(params);
    w_.prepare(!s_.restarted);
    if (!s_.restarted) volume.start(w_);
    if (!bodies.empty() && !s_.restarted) bodies.set_loads(body_loads(w_, bodies));

    ProbeSet probes(s_.c, s_.opts.out_dir, writer, s_.restarted ? std::optional<std::int64_t>(s_.start.step) : std::nullopt);
    PvdIndex pvd(s_.opts.out_dir / "particles.pvd");
    double time = s_.start.time;
    std::int64_t step = s_.start.step;
    if (s_.restarted && writer) pvd.load_existing(time);
    double dt = s_.restarted ? s_.start.dt : next_time_step();
    // The drive's mean velocity: exact sums over every slab's fluid (sample_centroid).
    auto mean_velocity = [&]() {
      const std::vector<double> centroid = sample_centroid(w_, -1);
      std::array<double, 3> u{0, 0, 0};
      for (int k = 0; k < s_.c.dim; ++k) u[k] = centroid[s_.c.dim + k];
      return u;
    };
    if (drive.on() && !s_.restarted) {
      drive.update(params, mean_velocity(), 0.0, dt);
      w_.set_params(params);
    }

    const double end_time = s_.opts.until.value_or(s_.c.end_time);
    const int checkpoint_every = s_.opts.checkpoint_every.value_or(s_.c.checkpoint_every);
    const double out_dt = s_.c.output_interval;
    const double probe_dt = s_.c.probe_interval;  // 0: every step
    double next_output = out_dt > 0 ? (s_.restarted ? next_on_grid(time, out_dt) : time) : INFINITY;
    double next_probe = probe_dt > 0 && s_.restarted ? next_on_grid(time, probe_dt) : time;
    std::int64_t taken = 0;
    std::int64_t last_snapshot = -1;
    const auto t0 = Clock::now();
    const std::int64_t total_particles = t_.sum(static_cast<std::int64_t>(w_.particles().owned()));
    Progress progress(writer && !s_.opts.quiet, total_particles);
    std::filesystem::path last_checkpoint;
    std::vector<double> imbalance_log;

    // At most one probe row and one snapshot per step, whatever the intervals.
    auto output = [&](bool final_step) {
      if (!probes.empty() && (probe_dt <= 0 || time >= next_probe - 1e-9 * probe_dt || final_step)) {
        probes.sample(time, step, w_, &motions, &bodies);
        if (probe_dt > 0) next_probe = next_on_grid(time, probe_dt);
      }
      if (out_dt > 0 && (time >= next_output - 1e-9 * out_dt || (final_step && last_snapshot != step))) {
        write_snapshot(pvd, time, step, "snapshots");
        last_snapshot = step;
        next_output = next_on_grid(time, out_dt);
      }
    };

    if (!s_.restarted) output(false);
    in_situ(step, time);
    std::string unstable;
    AppendFile steering_log;
    if (writer && s_.opts.steering) {
      const auto path = s_.opts.out_dir / "steering.log";
      write_file_atomically(path, "# spate steering log: <step> <time> <name> <values>; replay with --steering-log\n" +
                                      history_text(s_.steering_history));
      steering_log = AppendFile(path, false);
    }
    // Step boundary: poll the source on slab 0, share, validate and apply everywhere identically.
    auto steer_now = [&]() {
      if (!s_.opts.steering) return;
      std::vector<SteeringChange> asked;
      if (t_.slab() == 0) asked = s_.opts.steering->poll(step, time);
      for (auto& change : share_changes(t_, asked)) {
        change.step = step;
        change.time = time;
        if (auto why = validate(change, s_.c.dim, &motions, &s_.c)) {
          if (writer) spdlog::warn("steering: rejected {} at step {}: {}", change.name, step, *why);
          if (writer) ++s_.result.steering_rejected;
          continue;
        }
        apply(change, steer);
        if (change.name == "insitu_every" && s_.opts.insitu) s_.opts.insitu->set_interval(insitu_every);
        if (writer) {
          s_.steering_history.push_back(change);
          ++s_.result.steering_accepted;
          steering_log.append(to_log_line(change) + "\n");
          spdlog::info("steering: {} applied from step {}", to_log_line(change), step + 1);
        }
      }
      w_.set_params(params);
    };
    steer_now();
    // Fluid removed through open sides (open_sides(), particle_checks.hpp), with the restart's.
    std::int64_t removed = s_.start.removed;
    const double removed_limit = s_.c.max_removed_fraction * static_cast<double>(s_.result.particles.fluid);
    std::int64_t next_removal_warning = 1;
    int interrupted = 0;
    // What a summary written after a failure will say about how far the run got (the reporter).
    auto record_progress = [&]() {
      if (!reporter) return;
      s_.result.steps = taken;
      s_.result.final_step = step;
      s_.result.simulated_time = time;
      s_.result.last_checkpoint = last_checkpoint;
      s_.result.removed = removed;
    };
    record_progress();
    // One per process: whether its threads have the cores to themselves sets the grains of the
    // CPU backend's parallel loops (backend/cpu/parallel.hpp); the bits never depend on it.
    std::optional<cpu::CoreWatch> core_watch;
    if (reporter) core_watch.emplace(s_.omp_threads * s_.local_slabs);
    while (true) {
      if (steer.stop) {
        s_.result.stopped_by_steering = true;
        break;
      }
      if (s_.opts.steps ? taken >= *s_.opts.steps : time >= end_time - 1e-12) break;
      if (t_.slab_count() > 1 && balancing_pass_due(taken, step, s_.c.balance_every))
        imbalance_log.push_back(w_.rebalance(kMinColumnsPerSlab));
      if (motions.size() > 0) {  // the walls' rigid map over this step and their state at its end
        motions.set_step(params, time, time + dt);
        if (s_.c.tank_motion >= 0) w_.set_open_sides(tank_open_sides(open_sides_, motions, s_.c.tank_motion, time + dt));
        bodies.advance(time, time + dt);
        bodies.set_step(params);
        w_.set_params(params);
      }
      if (auto fault = w_.step(static_cast<float>(dt))) {
        unstable = describe(*fault, step + 1, time + dt);
        time += dt;
        ++step;
        break;
      }
      const double before = time;
      time += dt;
      ++step;
      ++taken;
      if (core_watch) core_watch->tick();
      record_progress();
      const StepReport report =
          share_report(t_, w_.health(static_cast<float>(s_.c.density_min_ratio), static_cast<float>(s_.c.density_max_ratio)),
                       w_.removed_ids(), stop_signal.load());
      if (!report.removed.empty()) {
        removed += static_cast<std::int64_t>(report.removed.size());
        if (reporter && s_.result.removed_first_ids.size() < kRemovedIdsKept)
          for (std::uint32_t id : report.removed)
            if (s_.result.removed_first_ids.size() < kRemovedIdsKept) s_.result.removed_first_ids.push_back(id);
        // One warning at the first removal and at every tenfold of the total after it.
        if (removed >= next_removal_warning) {
          if (writer) warn_removed(report.removed, removed, step, time);
          while (next_removal_warning <= removed) next_removal_warning *= 10;
        }
      }
      if (report.fault) {
        unstable = describe(*report.fault, step, time);
        break;
      }
      volume.hold(w_);
      if (static_cast<double>(removed) > removed_limit) {
        unstable = fmt::format("step {}, t = {:.6g} s: {} fluid particles ({:.3g} % of the fluid) have left the domain through "
                               "its open sides, more than tank.max_removed_fraction = {} allows",
                               step, time, removed, 100.0 * static_cast<double>(removed) / static_cast<double>(s_.result.particles.fluid),
                               s_.c.max_removed_fraction);
        break;
      }
      if (!(time > before)) {
        unstable = fmt::format("step {}, t = {:.17g} s: the time step {} s no longer advances the simulated time", step, time, dt);
        break;
      }
      if (!bodies.empty()) bodies.set_loads(body_loads(w_, bodies));
      const double dt_taken = dt;
      dt = next_time_step();
      if (!(dt > 0) || !std::isfinite(dt)) {
        unstable = fmt::format("step {}, t = {:.6g} s: the time step collapsed to {}", step, time, dt);
        break;
      }
      if (drive.on()) {
        drive.update(params, mean_velocity(), dt_taken, dt);
        w_.set_params(params);
      }
      interrupted = report.stop_signal;
      const bool last = interrupted || (s_.opts.steps ? taken >= *s_.opts.steps : time >= end_time - 1e-12);
      output(last);
      in_situ(step, time);  // before steering: the design applies steering after each in-situ step
      steer_now();
      if ((checkpoint_every > 0 && step % checkpoint_every == 0) || steer.checkpoint_now) {
        last_checkpoint = write_checkpoint_now(time, step, dt, removed);
        steer.checkpoint_now = false;
      }
      record_progress();
      progress.update(taken, time, end_time, s_.start.time, removed);
      if (interrupted) break;
    }
    progress.finish();
    const double stepping_seconds = std::chrono::duration<double>(Clock::now() - t0).count();

    if (!unstable.empty()) {
      write_snapshot(pvd, time, step, "diagnostic", /*index=*/false);
    } else if (last_checkpoint.empty() || !last_checkpoint.filename().string().ends_with(step_name(step) + ".h5")) {
      last_checkpoint = write_checkpoint_now(time, step, dt, removed);
    }
    record_progress();
    const auto counts = w_.slab_particle_counts();
    const std::vector<double> busy = t_.allgather_value(w_.busy_seconds());
    // Per-pass seconds of every slab (zeros unless SPATE_PASS_TIMERS=1; backend/pass_times.hpp).
    const std::vector<PassSeconds> pass_seconds = t_.allgather_value(w_.pass_seconds());
    const std::int64_t solver_bytes = t_.sum(static_cast<std::int64_t>(w_.allocated_bytes()));
    const std::int64_t ghosts = t_.sum(static_cast<std::int64_t>(w_.particles().ghosts()));
    if (reporter) {
      std::lock_guard lock(s_.result_mutex);
      RunResult& r = s_.result;
      r.steps = taken;
      r.final_step = step;
      r.simulated_time = time;
      r.wall_seconds = std::chrono::duration<double>(Clock::now() - t0).count();
      r.stepping_seconds = stepping_seconds;
      r.last_checkpoint = last_checkpoint;
      r.slab_particles = counts;
      r.slab_busy_seconds = busy;
      if (pass_timers_enabled()) r.slab_pass_seconds = pass_seconds;
      r.imbalance = imbalance(counts);
      r.ghosts = ghosts;
      r.bytes_per_particle = static_cast<double>(solver_bytes) / static_cast<double>(std::max<std::int64_t>(1, total_particles));
      r.imbalance_history = imbalance_log;
      r.closed_volume_scalings = volume.scalings();
      if (volume.on() && writer && !s_.opts.quiet) spdlog::info("density.closed_volume: the fluid's densities were scaled back to its volume {} times in {} steps",
                                              volume.scalings(), taken);
      r.migrated = w_.crossings();
      r.handed_over = w_.handovers();
      r.face_moves = w_.face_moves();
      if (s_.opts.insitu) r.insitu_failures = s_.opts.insitu->failures();
      if (!unstable.empty()) {
        r.exit_code = 3;
        r.exit_status = "unstable";
        r.message = unstable + "; diagnostic snapshot in " + (s_.opts.out_dir / "diagnostic").string() +
                    (last_checkpoint.empty() ? "" : "; last good checkpoint " + last_checkpoint.string());
      } else if (interrupted) {
        r.exit_code = 128 + interrupted;
        r.exit_status = "interrupted";
        r.message = fmt::format("stopped by signal {} ({}) at step {}, t = {:.6g} s; final checkpoint {}", interrupted,
                                interrupted == SIGINT ? "SIGINT" : interrupted == SIGTERM ? "SIGTERM" : "signal", step, time,
                                last_checkpoint.string());
      }
    }
  }

 private:
  void warn_removed(const std::vector<std::uint32_t>& ids, std::int64_t total, std::int64_t step, double time) const {
    std::string list;
    for (std::size_t k = 0; k < ids.size() && k < 5; ++k) list += (k ? ", " : "") + std::to_string(ids[k]);
    if (ids.size() > 5) list += ", ...";
    const bool one = ids.size() == 1;
    spdlog::warn("step {}, t = {:.6g} s: {} fluid particle{} left the domain through its open sides and {} removed (id{} {}); {} "
                 "removed so far ({:.3g} % of the fluid, tank.max_removed_fraction {})",
                 step, time, ids.size(), one ? "" : "s", one ? "was" : "were", one ? "" : "s", list, total,
                 100.0 * static_cast<double>(total) / static_cast<double>(std::max<std::int64_t>(1, s_.result.particles.fluid)),
                 s_.c.max_removed_fraction);
  }

  // In situ: every local slab stops at a barrier, the process's first local slab hands the views
  // of all local slabs to the sink, and nobody moves on until the pipelines are done with the
  // (zero-copy) arrays.
  void in_situ(std::int64_t step, double time) {
    InSituSink* sink = s_.opts.insitu;
    if (!sink || !sink->wants(step, time)) return;
    t_.barrier();
    const auto first = std::find_if(s_.workers.begin(), s_.workers.end(), [](SlabWorker* w) { return w != nullptr; });
    if (first != s_.workers.end() && *first == &w_) {
      std::vector<SlabView> views;
      for (std::size_t k = 0; k < s_.workers.size(); ++k)
        if (s_.workers[k]) views.push_back(slab_view(s_.workers[k]->particles(), s_.workers_first_slab + static_cast<int>(k), t_.slab_count(),
                                                    static_cast<int>(s_.c.fluids.size())));
      sink->execute(step, time, views);
    }
    t_.barrier();
  }

  double next_time_step() {
    if (s_.c.fixed_dt) return *s_.c.fixed_dt;
    TimeStepControl ctl;
    ctl.cfl = static_cast<float>(s_.c.cfl);
    return t_.min(static_cast<double>(w_.local_time_step(ctl)));
  }

  std::string describe(const ParticleFault& f, std::int64_t step, double time) const {
    return fmt::format("step {}, t = {:.6g} s: particle {} {}", step, time, f.id, f.what);
  }

  void write_snapshot(PvdIndex& pvd, double time, std::int64_t step, const std::string& folder, bool index = true) {
    const auto dir = s_.opts.out_dir / folder;
    const std::string piece = step_name(step) + "/slab_" + std::to_string(t_.slab()) + ".vtp";
    write_vtp_piece(dir / piece, w_.particles(), t_.slab(), static_cast<int>(s_.c.fluids.size()));
    t_.barrier();
    if (t_.slab() != 0) return;
    std::vector<std::string> pieces;
    for (int s = 0; s < t_.slab_count(); ++s) pieces.push_back(step_name(step) + "/slab_" + std::to_string(s) + ".vtp");
    FieldData field_data = case_constants(s_.c);
    field_data.insert(field_data.end(), {{"time", time}, {"step", static_cast<double>(step)}, {"TimeValue", time}});
    // The floating solids' state, so that spate post writes their body probes from snapshots too.
    if (bodies_) {
      const auto bodies = bodies_->field_data();
      field_data.insert(field_data.end(), bodies.begin(), bodies.end());
    }
    write_vtm(dir / (step_name(step) + ".vtm"), pieces, field_data);
    if (index) pvd.add(time, folder + "/" + step_name(step) + ".vtm");
    spdlog::debug("snapshot of step {} (t = {:.6g} s): {}", step, time, (dir / (step_name(step) + ".vtm")).string());
  }

  std::filesystem::path write_checkpoint_now(double time, std::int64_t step, double dt, std::int64_t removed) {
    // The writer's process is the one that holds slab 0.
    GatheredParticles all = gather_to_writer(w_, s_.workers, s_.workers_first_slab == 0);
    const auto dir = s_.opts.out_dir / "checkpoints";
    const auto path = dir / ("checkpoint_" + step_name(step) + ".h5");
    if (t_.slab() == 0) {
      CheckpointMeta meta;
      meta.step = step;
      meta.time = time;
      meta.dt = dt;
      meta.case_name = s_.c.name;
      meta.case_yaml = s_.c.source_yaml;
      meta.steering_log = history_text(s_.steering_history);
      meta.removed = removed;
      meta.geometry_hash = geometry_hash(s_.c);
      if (bodies_) meta.bodies = bodies_->save();
      if (drive_) meta.drive = drive_->save();
      if (volume_) meta.closed_volume = volume_->save();
      std::vector<std::vector<FieldRef>> fields;
      for (auto* slab : all.slabs) fields.push_back(slab->fields());
      write_checkpoint(path, meta, s_.c.dim, all.by_id.size(), [&](std::size_t k, char* out) {
        const std::size_t size = fields[0][k].elem_size;
        for (const auto& e : all.by_id) std::memcpy(out, fields[e.slab][k].bytes() + e.index * size, size), out += size;
      });
      spdlog::debug("checkpoint of step {} (t = {:.6g} s): {}", step, time, path.string());
      prune_checkpoints(path, step);
    }
    t_.barrier();
    return path;
  }

  // Retention (output.checkpoint_keep_last / keep_every, or the command line): of the checkpoints
  // this run wrote, the newest keep_last stay (0: all), and so does, for good, every one at a step
  // that is a multiple of keep_every x checkpoint_every; the others go, with their XDMF sidecars.
  // Files of earlier runs in a reused output folder are never touched (a restart may still need
  // them, and their step numbers say nothing about which is newer).
  void prune_checkpoints(const std::filesystem::path& just_written, std::int64_t step) {
    const int keep_last = s_.opts.checkpoint_keep_last.value_or(s_.c.checkpoint_keep_last);
    const std::int64_t keep_every = s_.opts.checkpoint_keep_every.value_or(s_.c.checkpoint_keep_every);
    const std::int64_t every = s_.opts.checkpoint_every.value_or(s_.c.checkpoint_every);
    if (written_.empty() || written_.back().first != just_written)
      written_.emplace_back(just_written, keep_every > 0 && every > 0 && step % (keep_every * every) == 0);
    if (keep_last <= 0) return;
    for (std::size_t k = 0; k + static_cast<std::size_t>(keep_last) < written_.size();) {
      if (written_[k].second) {
        ++k;
        continue;
      }
      // An old checkpoint that cannot be removed costs space, not results: said, not fatal.
      std::error_code ec;
      std::filesystem::remove(written_[k].first, ec);
      if (!ec) std::filesystem::remove(xdmf_sidecar(written_[k].first), ec);
      if (ec) spdlog::warn("{}: cannot remove an old checkpoint: {}", written_[k].first.string(), ec.message());
      spdlog::debug("checkpoint {} removed (retention)", written_[k].first.string());
      written_.erase(written_.begin() + static_cast<std::ptrdiff_t>(k));
    }
  }

  std::vector<std::pair<std::filesystem::path, bool>> written_;  // this run's checkpoints, oldest first; kept for good
  Shared& s_;
  SlabTransport& t_;
  SlabWorker w_;
  OpenSides open_sides_;  // the tank's at t = 0 (tank_open_sides moves them with a moving tank)
  const RigidBodies* bodies_ = nullptr;  // the run's floating solids (for checkpoints)
  const FlowDrive* drive_ = nullptr;      // the run's flow drive (for checkpoints)
  const ClosedVolume* volume_ = nullptr;  // the run's held volume (for checkpoints)
};

}  // namespace

Simulation::Simulation(Case c, RunOptions options) : case_(std::move(c)), options_(std::move(options)) {}

void request_stop(int signal) noexcept { stop_signal.store(signal); }

RunResult Simulation::run() {
  // Surface tension's colour gradient, shifting's displacement and heat transfer's temperature are
  // optional fields: only the stores of a run that needs them carry them (made before the first of
  // them, in Shared).
  const OptionalFields optional_fields(FieldGroups{optional_field_groups(physics_params(case_))});
  Shared s(case_, options_);
  s.lattice = make_lattice(case_);
  s.params = physics_params(case_);
  if (options_.devices < 1) throw InputError(fmt::format("--devices {}: must be at least 1", options_.devices));
  if (options_.backend != "cpu" && options_.backend != "cuda")
    throw InputError(fmt::format("--backend {}: expected 'cpu' or 'cuda'", options_.backend));
  if (options_.backend == "cuda" && case_.closed_volume)
    throw InputError("--backend cuda: the case's density.closed_volume is held on the CPU backend only (sim/closed_volume.hpp); "
                     "run it with --backend cpu");
  if (options_.backend == "cuda") {
    try {
      gpu::require_device();
    } catch (const std::runtime_error& e) {
      throw InputError(fmt::format("--backend cuda: {}", e.what()));
    }
  }
  const ProcessGroup& group = process_group();
  // R ranks x D devices: global slab = rank * D + local device (docs/decomposition.md).
  const int local_slabs = options_.devices;
  const int slabs = group.ranks * local_slabs;
  s.layout = SlabLayout::uniform(s.lattice.cells[0], slabs);
  if (s.layout.narrowest() < kMinColumnsPerSlab) {
    const std::string split = group.ranks > 1 ? fmt::format("{} ranks x --devices {} = {} slabs", group.ranks, local_slabs, slabs)
                                              : fmt::format("--devices {}", slabs);
    throw InputError(fmt::format("{}: the domain is {} cells long in x; every slab needs at least {} cells, so at most {} slabs",
                                 split, s.lattice.cells[0], kMinColumnsPerSlab, s.lattice.cells[0] / kMinColumnsPerSlab));
  }
  // Nothing is allocated before the run is known to fit (docs/cli.md, memory).
  try {
    require_memory_for(case_, group.ranks, group.ranks_on_node);
    if (options_.backend == "cuda") require_device_memory_for(case_, options_.devices);
  } catch (const CaseError& e) {
    throw InputError(e.what());
  }
  const ParticleCounts expected = count_particles(case_);
  if (options_.restart) {
    try {
      s.start = read_checkpoint(*options_.restart, s.initial, &case_);
    } catch (const std::exception& e) {
      throw InputError(e.what());
    }
    s.restarted = true;
    s.steering_history = s.start.steering_history;  // checked by read_checkpoint
    try {
      RigidBodies(case_).restore(s.start.bodies);
    } catch (const std::exception& e) {
      throw InputError(fmt::format("{}: attribute 'bodies': {}", options_.restart->string(), e.what()));
    }
    try {
      FlowDrive(case_).restore(s.start.drive);
    } catch (const std::exception& e) {
      throw InputError(fmt::format("{}: attribute 'drive': {}", options_.restart->string(), e.what()));
    }
    try {
      ClosedVolume(case_).restore(s.start.closed_volume);
    } catch (const std::exception& e) {
      throw InputError(fmt::format("{}: attribute 'closed_volume': {}", options_.restart->string(), e.what()));
    }
  } else {
    s.initial = relax_particles(case_, generate_particles(case_));  // as generated unless `relax:` asks
  }
  s.result.particles = expected;
  if (slabs > 1 && case_.balanced_start)
    s.layout = balanced_layout(column_costs(s.initial, s.lattice, s.params.materials), slabs, kMinColumnsPerSlab);  // start balanced
  // --threads counts the threads of this process; by default the cores are shared among the
  // ranks on this machine, then among the device workers (at least one thread each).
  const int hw = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  const int threads = options_.threads > 0 ? options_.threads : std::max(1, hw / group.ranks_on_node);
  s.omp_threads = std::max(1, threads / local_slabs);
  s.local_slabs = local_slabs;
  s.workers.assign(local_slabs, nullptr);
  // The output folder is the last input checked: an unusable one is bad input (exit 2). From here
  // on every outcome ends in a result and a summary.json.
  try {
    create_output_folder(options_.out_dir);
    AtomicFile probe(options_.out_dir / ".spate_write_test");  // removed again: nothing committed
    // The effective case (file plus --set), for spate post and for the record.
    if (group.rank == 0)
      write_file_atomically(options_.out_dir / "case.yaml", "# The effective case of the run in this folder (" + case_.file +
                                                                " with --set applied), written by spate run.\n" + case_.source_yaml + "\n");
    // The solids' surfaces at the start, geometry/solid_<material>.vtp, for drawing them: the
    // in-situ free surface (pipelines/free_surface.py) and ParaView beside the snapshots; every
    // shaped solid's, and a moving box solid's box. A solid that moves (prescribed or floating)
    // also gets the start positions of its particles with their ids, solid_<material>_start.vtp:
    // the pipeline fits the rigid motion that carries them to where they are now and draws the
    // surface there.
    if (group.rank == 0) write_solid_geometry(case_, options_.out_dir, s.restarted ? nullptr : &s.initial);
  } catch (const OutputError& e) {
    throw InputError(fmt::format("--out {}: the output folder is not usable: {}", options_.out_dir.string(), e.what()));
  }

  std::unique_ptr<LocalSlabs> local;
#ifdef SPATE_WITH_MPI
  if (group.mpi) local = make_mpi_slabs(local_slabs);
#endif
  if (!local) local = std::make_unique<InProcessHub>(local_slabs);
  s.workers_first_slab = local->first_slab();
  std::vector<std::exception_ptr> errors(local_slabs);  // kept whole: bad input (exit 2) must stay InputError
  auto body = [&](int d) {
    try {
      auto t = local->endpoint(d, s.lattice.periodic[0]);
      Worker(s, *t).run();
    } catch (const PeerFailure&) {
      local->abandon();
    } catch (...) {
      errors[d] = std::current_exception();
      local->abandon();
    }
  };
  // Local slab 0 runs on this (the main) thread: with MPI it is the one worker that calls MPI, and
  // in-situ consumers (VTK, ParaView's Python), which slab 0 calls, only work on the main thread.
  std::vector<std::thread> pool;
  for (int d = 1; d < local_slabs; ++d) pool.emplace_back(body, d);
  body(0);
  for (auto& th : pool) th.join();
  for (int d = 0; d < local_slabs; ++d) {
    if (!errors[d]) continue;
    RunResult& r = s.result;
    const std::string where = group.ranks > 1 ? fmt::format("slab {} (rank {}): ", s.workers_first_slab + d, group.rank) : "";
    try {
      std::rethrow_exception(errors[d]);
    } catch (const InputError&) {
      throw;
    } catch (const OutputError& e) {
      r.exit_code = 5;
      r.exit_status = "output_failed";
      r.message = where + "an output could not be written: " + e.what();
    } catch (const std::filesystem::filesystem_error& e) {
      r.exit_code = 5;
      r.exit_status = "output_failed";
      r.message = where + "an output could not be written: " + e.what();
    } catch (const std::bad_alloc&) {
      r.exit_code = 6;
      r.exit_status = "out_of_memory";
      r.message = where + fmt::format("out of memory (the estimate for this run was {}; other processes may have taken memory since)",
                                      format_bytes(static_cast<double>(estimate_run_memory(case_, group.ranks, group.ranks_on_node).bytes)));
    } catch (const std::exception& e) {
      r.exit_code = 4;
      r.exit_status = "internal_error";
      r.message = where + "internal error: " + e.what();
    } catch (...) {
      r.exit_code = 4;
      r.exit_status = "internal_error";
      r.message = where + "internal error: an exception that is not a std::exception";
    }
    r.message += fmt::format(" (at step {}, t = {:.6g} s{})", r.final_step, r.simulated_time,
                             r.last_checkpoint.empty() ? "" : "; last checkpoint " + r.last_checkpoint.string());
    break;
  }
  return s.result;
}

}  // namespace spate
