#include "commands.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <numbers>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>
#include <thread>
#include <unistd.h>

#include "backend/cpu/cpu_backend.hpp"
#include "backend/cpu/interaction_count.hpp"
#include "backend/cuda/device_plan.hpp"
#include "backend/cuda/device_runtime.hpp"
#include "backend/cuda/halo_exchange.hpp"
#include "backend/pass_times.hpp"
#include "case/case.hpp"
#include "case/generator.hpp"
#include "case/thin_features.hpp"
#include "comm/in_process_transport.hpp"
#include "comm/process_group.hpp"
#include "io/checkpoint.hpp"
#include "io/field_scale.hpp"
#include "io/output_file.hpp"
#include "io/run_summary.hpp"
#include "sim/memory_estimate.hpp"
#include "sim/simulation.hpp"
#include "sim/slab_worker.hpp"
#ifdef SPATE_WITH_CATALYST
#include "catalyst_sink.hpp"
#include "catalyst_steering.hpp"
#endif

namespace spate::app {

namespace {

Case load(const std::string& file, const std::vector<std::string>& overrides) {
  try {
    return load_case(file, overrides);
  } catch (const CaseError& e) {
    throw BadInput(e.what());
  }
}

void check_backend(const std::string& backend) {
  if (backend == "cpu") return;
  if (backend == "cuda") {
    try {
      gpu::require_device();
    } catch (const std::runtime_error& e) {
      throw BadInput(fmt::format("--backend cuda: {}", e.what()));
    }
    return;
  }
  throw BadInput(fmt::format("--backend {}: expected 'cpu' or 'cuda'", backend));
}

#ifdef SPATE_WITH_CATALYST
// Timing of the in-situ steps: a line on stdout and insitu.json beside summary.json.
void report_insitu(const catalyst::CatalystSink& sink, const std::filesystem::path& out_dir) {
  const catalyst::InSituTiming t = sink.timing();
  const double n = static_cast<double>(std::max<std::int64_t>(1, t.steps));
  nlohmann::ordered_json j;
  j["insitu_steps"] = t.steps;
  j["adaptor_seconds_per_step"] = t.adaptor_seconds / n;
  j["adaptor_seconds_each_step"] = t.adaptor_step_seconds;
  j["pipelines_seconds_per_step"] = t.pipelines_seconds / n;
  j["pipelines_seconds_each_step"] = t.pipelines_step_seconds;
  j["solver_wait_seconds_each_step"] = t.solver_wait_step_seconds;
  j["script_seconds_per_step"] = nlohmann::json::array();
  for (double s : t.script_seconds) j["script_seconds_per_step"].push_back(s / n);
  j["failures"] = sink.failures();
  j["incidents"] = sink.incidents();
  j["isolated"] = sink.isolated();
  write_file_atomically(out_dir / "insitu.json", j.dump(2) + "\n");
  spdlog::info("in situ: {} steps, adaptor {:.3g} ms/step, pipelines {:.3g} s/step", t.steps, 1e3 * t.adaptor_seconds / n,
               t.pipelines_seconds / n);
}
#endif

// --live [HOST:]PORT -> "host:port" (host defaults to localhost). Exit 2 on anything else.
std::string live_address(const std::string& arg) {
  const std::string text = arg.empty() ? "localhost:22222" : arg;
  const auto colon = text.rfind(':');
  const std::string host = colon == std::string::npos ? "localhost" : text.substr(0, colon);
  const std::string port = colon == std::string::npos ? text : text.substr(colon + 1);
  const bool digits = !port.empty() && port.size() <= 5 && port.find_first_not_of("0123456789") == std::string::npos;
  const long number = digits ? std::stol(port) : 0;
  if (host.empty() || host.find_first_of(" /?&") != std::string::npos || number < 1 || number > 65534)
    throw BadInput(fmt::format("--live {}: expected [HOST:]PORT with PORT in 1..65534 (e.g. localhost:22222)", text));
  return host + ":" + port;
}

#ifdef SPATE_WITH_CATALYST
// pipelines/ (live.py, spate_steering.xml): $SPATE_PIPELINES_DIR, else the data folder's.
std::filesystem::path pipelines_dir() {
  const char* env = std::getenv("SPATE_PIPELINES_DIR");
  return env && *env ? std::filesystem::path(env) : data_dir() / "pipelines";
}
#endif

// Thin fluid features (case/thin_features.hpp), each a warning; returns the messages.
std::vector<std::string> warn_thin_features(const Case& c) {
  std::vector<std::string> messages;
  for (const ThinFeature& f : thin_features(c)) messages.push_back(c.file + ": " + f.message(c.dp));
  if (process_group().rank == 0)
    for (auto& m : messages) spdlog::warn("{}", m);
  return messages;
}

}  // namespace

int hardware_threads() { return static_cast<int>(std::max(1u, std::thread::hardware_concurrency())); }

namespace {

// SIGINT (Ctrl-C) and SIGTERM (a batch system's notice) stop the run at the next step boundary with
// its final checkpoint and summary (exit 128 + signal); a second one ends it at once.
extern "C" void on_stop_signal(int signal) {
  spate::request_stop(signal);
  std::signal(signal, SIG_DFL);
}

}  // namespace

std::filesystem::path data_dir() {
  const char* env = std::getenv("SPATE_DATA_DIR");
  if (env && *env) return env;
  std::error_code ec;
  const auto exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  const auto installed = exe.parent_path().parent_path() / "share" / "spate";
  if (!ec && std::filesystem::is_directory(installed / "pipelines", ec)) return installed;
  return SPATE_SOURCE_DIR;
}

#ifdef SPATE_WITH_CATALYST
std::unique_ptr<catalyst::CatalystSink> make_catalyst_sink(catalyst::CatalystOptions co, const Case& c) {
  co.constants = case_constants(c);
  co.timeout = c.insitu_timeout;
  try {
    create_output_folder(co.working_dir);
  } catch (const OutputError& e) {
    throw BadInput(fmt::format("the output folder {} is not usable: {}", co.working_dir.string(), e.what()));
  }
  try {
    return std::make_unique<catalyst::CatalystSink>(std::move(co));
  } catch (const catalyst::InSituLoadError& e) {
    throw BadInput(e.what());
  }
}
#endif

namespace {

// Where a run that ends early leaves its summary.json: the output folder as soon as it is known
// (--out at once, out/<case name> once the case is read).
struct RunRecord {
  std::filesystem::path out_dir;
  std::string case_name;
  bool summary_written = false;
  std::unique_ptr<OutputFolderLock> lock;  // held from the moment the folder is known to the end
};

int run_case(const RunArgs& a, RunRecord& record) {
  Case c = load(a.case_file, a.overrides);
  record.case_name = c.name;
  if (a.out.empty()) record.out_dir = std::filesystem::path("out") / c.name;
  // The folder is this run's from here on. A second run into it is refused (exit 2) and writes
  // nothing there: its summary.json would replace the first run's.
  if (process_group().rank == 0) {
    try {
      record.lock = std::make_unique<OutputFolderLock>(record.out_dir);
    } catch (const OutputFolderBusy&) {
      record.summary_written = true;
      throw BadInput(fmt::format("--out {}: another spate run is writing into this folder; wait for it to end or choose another --out",
                                 record.out_dir.string()));
    } catch (const OutputError&) {
      // Not usable: the simulation's own check of the folder says why (exit 2).
    }
  }
  check_backend(a.backend);
  const std::vector<std::string> warnings = warn_thin_features(c);
  // In situ: the command line replaces the case file's `insitu:` section.
  const std::vector<std::string> pipelines = a.pipelines.empty() ? c.insitu_pipelines : a.pipelines;
  [[maybe_unused]] const int insitu_every = a.insitu_every.value_or(c.insitu_every);
#ifndef SPATE_WITH_CATALYST
  if (!pipelines.empty() || a.insitu_every)
    throw BadInput("--pipeline/--insitu-every (or the case's insitu: section): this spate was built without ParaView Catalyst");
#endif
  if (a.insitu_every && *a.insitu_every < 1) throw BadInput(fmt::format("--insitu-every {}: must be at least 1", *a.insitu_every));
  // Live: the simulation connects out to a listening ParaView; it never listens itself.
  const bool live = a.live_requested || !a.live.empty();
  std::string live_url;
#ifndef SPATE_WITH_CATALYST
  if (live) throw BadInput("--live: this spate was built without ParaView Catalyst (Catalyst Live needs it)");
#endif
  if (live) live_url = live_address(a.live);
  if (live && !a.steering_log.empty())
    throw BadInput("--live and --steering-log: a run is steered live or replays a log, not both");
  if (a.steps && *a.steps < 0) throw BadInput(fmt::format("--steps {}: must be >= 0", *a.steps));
  if (a.until && !(*a.until > 0)) throw BadInput(fmt::format("--until {}: must be > 0", *a.until));
  if (a.threads < 0) throw BadInput(fmt::format("--threads {}: must be >= 0 (0: all cores)", a.threads));
  if (a.devices < 1) throw BadInput(fmt::format("--devices {}: must be at least 1", a.devices));
  if (a.checkpoint_every && *a.checkpoint_every < 0)
    throw BadInput(fmt::format("--checkpoint-every {}: must be >= 0", *a.checkpoint_every));
  if (a.checkpoint_keep_last && *a.checkpoint_keep_last < 0)
    throw BadInput(fmt::format("--checkpoint-keep-last {}: must be >= 0 (0: keep all)", *a.checkpoint_keep_last));
  if (a.checkpoint_keep_every && *a.checkpoint_keep_every < 0)
    throw BadInput(fmt::format("--checkpoint-keep-every {}: must be >= 0 (0: none)", *a.checkpoint_keep_every));

  RunOptions o;
  o.out_dir = record.out_dir;
  if (a.steps) o.steps = *a.steps;
  o.until = a.until;
  o.threads = a.threads;
  o.devices = a.devices;
  o.backend = a.backend;
  o.checkpoint_every = a.checkpoint_every;
  o.checkpoint_keep_last = a.checkpoint_keep_last;
  o.checkpoint_keep_every = a.checkpoint_keep_every;
  if (!a.restart.empty()) o.restart = a.restart;
  o.quiet = a.quiet;
  std::unique_ptr<SteeringReplay> replay;
  if (!a.steering_log.empty()) {
    try {
      replay = std::make_unique<SteeringReplay>(read_log(a.steering_log, c.dim));
    } catch (const std::exception& e) {
      throw BadInput(std::string("--steering-log: ") + e.what());
    }
    o.steering = replay.get();
  }

#ifdef SPATE_WITH_CATALYST
  std::unique_ptr<catalyst::CatalystSink> insitu;
  if (!pipelines.empty() || live) {
    catalyst::CatalystOptions co;
    co.scripts.assign(pipelines.begin(), pipelines.end());
    co.every = insitu_every;
    co.working_dir = o.out_dir;
    if (live) {
      catalyst::LiveOptions lo;
      lo.url = live_url;
      lo.script = pipelines_dir() / "live.py";
      lo.xml = pipelines_dir() / "spate_steering.xml";
      lo.handshake_timeout = c.insitu_live_timeout;
      // pipelines/live.py reads the address from the environment (ParaView scripts take no arguments).
      ::setenv("SPATE_LIVE_URL", live_url.c_str(), 1);
      catalyst::SteeringInitial& init = lo.initial;
      // The case's own (double) values: they survive ParaView's state round trips unchanged, so an
      // untouched parameter never shows up as a change.
      for (int k = 0; k < 3; ++k) init.gravity[k] = k < c.dim ? c.gravity[k] : 0.0;
      init.viscosity = c.fluids[0].viscosity;
      init.phase_viscosity = {0.0, c.fluids[0].viscosity};
      init.artificial_viscosity = c.artificial_viscosity;
      init.insitu_every = insitu_every;
      if (!c.motions.empty()) init.motion_frequency = {0.0, MotionSet(c.motions, c.dim).frequency(0)};
      // The first tank face that holds a temperature, and the first with a heat flux.
      for (int f = 5; f >= 0; --f) {
        const FaceThermalSpec& face = c.tank_faces[f];
        if (face.kind == ThermalCondition::FaceTemperature) init.face_temperature = {double(f), face.value};
        if (face.kind == ThermalCondition::FaceFlux) init.face_heat_flux = {double(f), face.value};
      }
      // The first spring of the floating solids, and the first hinged one.
      for (const BodySpec& b : c.bodies)
        if (!b.springs.empty()) {
          init.spring_stiffness = {0.0, b.springs[0].stiffness};
          init.spring_damping = {0.0, b.springs[0].damping};
          break;
        }
      for (std::size_t b = 0; b < c.bodies.size(); ++b)
        if (c.bodies[b].hinge.on) {
          init.hinge_stiffness = {double(b), c.bodies[b].hinge.stiffness};
          init.hinge_damping = {double(b), c.bodies[b].hinge.damping};
          break;
        }
      // A restart continues steered (the checkpoint holds the accepted changes): show those values.
      if (o.restart) {
        try {
          ParticleStore ignored;
          const CheckpointMeta meta = read_checkpoint(*o.restart, ignored);
          for (const SteeringChange& ch : meta.steering_history) init.take(ch);
        } catch (const std::exception&) {
          // an unreadable checkpoint is reported by the run itself (exit 2)
        }
      }
      co.live = lo;
    }
    insitu = make_catalyst_sink(std::move(co), c);
    o.insitu = insitu.get();
    if (live) {
      o.steering = insitu->steering();
      spdlog::info("live: connecting out to ParaView at {} on every in-situ step (Catalyst > Connect there)", live_url);
    }
  }
#endif

  RunResult r;
  std::signal(SIGINT, on_stop_signal);
  std::signal(SIGTERM, on_stop_signal);
  std::string bad_input;  // found once the run had written outputs: a pipeline that fails to load
  try {
    r = Simulation(c, o).run();
#ifdef SPATE_WITH_CATALYST
  } catch (const catalyst::InSituLoadError& e) {
    bad_input = e.what();
    r.exit_code = 2;
    r.exit_status = "bad_input";
    r.message = bad_input;
    r.insitu_failures = insitu->failures();
#endif
  } catch (const InputError& e) {
    throw BadInput(e.what());  // before any output (a bad restart file): no output folder
  } catch (const CaseError& e) {
    throw BadInput(e.what());
  }
  // Every rank knows the outcome; rank 0 reports it. A rank that failed itself (exit 4 to 6) also
  // writes the summary: under mpirun its failure ends the other ranks before they could.
  const ProcessGroup& group = process_group();
  const bool own_failure = r.exit_code >= 4 && r.exit_code <= 6;
  if (group.rank != 0 && !own_failure) {
    if (!bad_input.empty()) throw BadInput(bad_input);
    return r.exit_code;
  }
#ifdef SPATE_WITH_CATALYST
  try {
    if (insitu && group.rank == 0) report_insitu(*insitu, o.out_dir);
  } catch (const OutputError& e) {
    spdlog::error("{}", e.what());
    if (r.exit_code == 0) r.exit_code = 5;
  }
#endif
  SummaryExtras x;
  x.threads = a.threads > 0 ? a.threads : std::max(1, hardware_threads() / group.ranks_on_node);
  x.devices = a.devices;
  x.backend = a.backend;
  x.ranks = group.ranks;
  x.warnings = warnings;
  // The summary is written whatever happened; if even that fails (a full disk), the run failed to
  // deliver its outputs (exit 5) unless it had failed already.
  try {
    write_summary(o.out_dir / "summary.json", c, physics_params(c), r, x);
    record.summary_written = true;
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    if (r.exit_code == 0 || r.exit_code == 3) r.exit_code = 5;
  }
  if (!bad_input.empty()) throw BadInput(bad_input);
  if (r.exit_code == 3) {
    spdlog::error("the run went unstable: {}", r.message);
  } else if (r.exit_code != 0) {
    spdlog::error("{}", r.message);
  } else {
    const std::string removed =
        r.removed > 0 ? fmt::format("; {} fluid particle{} removed through open sides", r.removed, r.removed == 1 ? "" : "s") : "";
    spdlog::info("{} done: {} steps to t = {:.6g} s in {:.2f} s ({:.3g} particle-steps/s){}; outputs in {}", c.name, r.steps,
                 r.simulated_time, r.wall_seconds,
                 r.wall_seconds > 0 ? r.steps * static_cast<double>(r.particles.total()) / r.wall_seconds : 0.0, removed,
                 o.out_dir.string());
  }
  return r.exit_code;
}

}  // namespace

int run_command(const RunArgs& a) {
  // Every run that got past argument parsing leaves a summary.json, whatever happened: here the
  // runs that ended before the simulation could write its own (bad input, exit 2, or an internal
  // error, exit 4), wherever the output folder is known and usable. The exception goes on to main().
  RunRecord record;
  if (!a.out.empty()) record.out_dir = a.out;
  auto leave_summary = [&](const char* status, int code, const std::string& message) {
    if (record.summary_written || record.out_dir.empty() || process_group().rank != 0) return;
    if (!record.lock && OutputFolderLock::held_elsewhere(record.out_dir)) return;  // another run's folder
    try {
      write_refusal_summary(record.out_dir / "summary.json", record.case_name, a.case_file, status, code, message);
    } catch (const std::exception& e) {
      spdlog::debug("no summary.json for this run: {}", e.what());  // e.g. --out is a file: said already
    }
  };
  try {
    return run_case(a, record);
  } catch (const BadInput& e) {
    leave_summary("bad_input", 2, e.what());
    throw;
  } catch (const std::filesystem::filesystem_error& e) {
    leave_summary("bad_input", 2, e.what());
    throw;
  } catch (const std::exception& e) {
    leave_summary("internal_error", 4, std::string("internal error: ") + e.what());
    throw;
  }
}

// Every shape of the case (a shaped tank, solids, fluid blocks), named as its key ("solids[0]
// 'column'").
template <class Visit>
void for_each_shape(const Case& c, Visit&& visit) {
  if (c.tank_shape) visit(std::string("tank"), *c.tank_shape);
  for (std::size_t k = 0; k < c.solids.size(); ++k)
    if (c.solids[k].shape) visit(fmt::format("solids[{}] '{}'", k, c.solids[k].name), *c.solids[k].shape);
  for (std::size_t k = 0; k < c.fluid_blocks.size(); ++k)
    if (c.fluid_blocks[k].shape) visit(fmt::format("fluid_blocks[{}]", k), *c.fluid_blocks[k].shape);
}

int info_command(const InfoArgs& a) {
  Case c = load(a.case_file, a.overrides);
  if (a.backend != "cpu" && a.backend != "cuda") throw BadInput(fmt::format("--backend {}: expected 'cpu' or 'cuda'", a.backend));
  if (a.devices < 1) throw BadInput(fmt::format("--devices {}: must be at least 1", a.devices));
  const std::vector<ThinFeature> thin = thin_features(c);
  if (!a.json) warn_thin_features(c);
  const ParticleCounts n = count_particles(c);
  if (n.fluid == 0) throw BadInput(c.file + ": the case generates no fluid particles (check fluid_blocks, wet_bed and dp)");
  const PhysicsParams P = physics_params(c);
  const Lattice L = make_lattice(c);
  const FluidMaterial& fluid = P.materials.fluid[0];
  const double dt = c.fixed_dt ? *c.fixed_dt : c.cfl * P.h / fluid.c0;
  const std::vector<std::string> names = material_names(c);
  // The case's optional fields (surface tension's, heat transfer's) count, as in its run.
  const OptionalFields optional_fields(FieldGroups{optional_field_groups(P)});
  const std::size_t bpp = ParticleStore(c.dim).bytes_per_particle();
  const double memory = static_cast<double>(n.total()) * bpp;
  const MemoryEstimate run_memory = estimate_run_memory(c, process_group().ranks, process_group().ranks_on_node);
  const AvailableMemory available = available_memory();
  // The GPU estimate needs no device: it is arithmetic on the case (backend/cuda/device_plan.hpp).
  std::vector<gpu::SlabMemory> per_gpu;
  if (a.backend == "cuda") per_gpu = gpu::device_memory_per_slab(L, n.total(), a.devices);
  std::size_t gpu_peak = 0;
  for (auto& m : per_gpu) gpu_peak = std::max(gpu_peak, m.bytes);
  if (a.json) {
    nlohmann::ordered_json j;
    j["case"] = c.name;
    j["dimensions"] = c.dim;
    j["particles"] = {{"fluid", n.fluid}, {"wall", n.wall}, {"total", n.total()}};
    j["dp"] = c.dp;
    j["smoothing_length"] = P.h;
    j["sound_speed"] = fluid.c0;
    j["sound_speed_automatic"] = !c.fluids[0].sound_speed.has_value();
    nlohmann::ordered_json materials = nlohmann::ordered_json::array();
    for (int m = 0; m < P.materials.count; ++m) {
      nlohmann::ordered_json e{{"index", m}, {"name", names[m]}, {"kind", P.is_fluid(m) ? "fluid" : m == P.materials.tank() ? "tank" : "solid"}};
      if (P.is_fluid(m)) {
        const FluidMaterial& f = P.materials.of(m);
        e["rest_density"] = f.rho0;
        e["particle_mass"] = f.mass;
        e["viscosity"] = f.viscosity;
        e["sound_speed"] = f.c0;
        e["tait_exponent"] = f.gamma;
        e["background_pressure"] = f.background_pressure;
      }
      if (!P.is_fluid(m)) e["motion"] = P.materials.motion[m] > 0 ? nlohmann::ordered_json(P.materials.motion[m] - 1) : nlohmann::ordered_json();
      materials.push_back(e);
    }
    j["materials"] = materials;
    nlohmann::ordered_json shapes = nlohmann::ordered_json::array();
    for_each_shape(c, [&](const std::string& owner, const Shape& s) {
      shapes.push_back({{"owner", owner},
                        {"description", s.description},
                        {"triangles", s.triangles},
                        {"bounds_min", std::vector<double>(s.lo.begin(), s.lo.begin() + c.dim)},
                        {"bounds_max", std::vector<double>(s.hi.begin(), s.hi.begin() + c.dim)},
                        {c.dim == 2 ? "perimeter" : "surface_area", s.area}});
    });
    j["shapes"] = shapes;
    nlohmann::ordered_json motions = nlohmann::ordered_json::array();
    for (std::size_t k = 0; k < c.motions.size(); ++k) {
      const MotionSpec& ms = c.motions[k];
      nlohmann::ordered_json e{{"index", k}, {"body", ms.body},
                               {"type", ms.floating >= 0 ? "floating" : ms.sinusoid() ? "sinusoid" : "time_series"}};
      if (ms.floating >= 0) {
        const BodySpec& b = c.bodies[ms.floating];
        const char* dofs[6] = {"x", "y", "z", "rx", "ry", "rz"};
        std::vector<std::string> free;
        for (int f = 0; f < 6; ++f)
          if (b.free[f]) free.push_back(dofs[f]);
        e["mass"] = b.mass;
        e["centre_of_mass"] = std::vector<double>(b.centre_of_mass.begin(), b.centre_of_mass.begin() + c.dim);
        e["inertia"] = c.dim == 2 ? nlohmann::ordered_json(b.inertia[2]) : nlohmann::ordered_json(b.inertia);
        e["free"] = free;
        motions.push_back(e);
        continue;
      }
      if (ms.sinusoid()) {
        e["period"] = 2.0 * std::numbers::pi / ms.omega;
        e["translation_amplitude"] = std::vector<double>(ms.translation.begin(), ms.translation.begin() + c.dim);
        e["rotation_amplitude_degrees"] = ms.rotation * 180.0 / std::numbers::pi;
        e["phase_degrees"] = ms.phase * 180.0 / std::numbers::pi;
      } else {
        e["file"] = ms.file;
        e["samples"] = ms.times.size();
        e["from"] = ms.times.front();
        e["to"] = ms.times.back();
      }
      e["axis"] = ms.axis;
      e["centre"] = std::vector<double>(ms.centre.begin(), ms.centre.begin() + c.dim);
      e["ramp"] = ms.ramp;
      e["end"] = ms.end ? nlohmann::ordered_json(*ms.end) : nlohmann::ordered_json();
      e["end_ramp"] = ms.end_ramp;
      motions.push_back(e);
    }
    j["motions"] = motions;
    if (c.drive.on)
      j["drive"] = {{"mean_velocity", std::vector<double>(c.drive.mean_velocity.begin(), c.drive.mean_velocity.begin() + c.dim)},
                    {"response_time", c.drive.response_time}};
    j["turbulence"] = c.sps ? nlohmann::ordered_json{{"model", "sps"}, {"smagorinsky", c.smagorinsky}, {"isotropic", c.sps_isotropic}}
                            : nlohmann::ordered_json{{"model", "none"}};
    j["dt"] = dt;
    j["dt_adaptive"] = !c.fixed_dt.has_value();
    j["cells"] = {L.cells[0], L.cells[1], L.cells[2]};
    j["bytes_per_particle"] = bpp;
    j["memory_bytes"] = memory;
    j["run_memory_bytes"] = run_memory.bytes;
    j["memory_available_bytes"] = available.bytes;
    j["memory_fits"] = run_memory.bytes <= available.bytes;
    j["backend"] = a.backend;
    j["warnings"] = nlohmann::ordered_json::array();
    for (const ThinFeature& f : thin)
      j["warnings"].push_back({{"key", f.key}, {"what", f.what}, {"thickness", f.thickness}, {"layers", f.layers},
                               {"resolving_dp", f.resolving_dp}, {"message", c.file + ": " + f.message(c.dp)}});
    if (a.backend == "cuda") {
      j["device_bytes_per_particle"] = gpu::device_footprint(c.dim).per_particle();
      j["devices"] = a.devices;
      nlohmann::ordered_json slabs = nlohmann::ordered_json::array();
      for (auto& m : per_gpu)
        slabs.push_back({{"device", m.slab}, {"owned", m.owned}, {"ghosts", m.ghosts}, {"capacity", m.capacity}, {"bytes", m.bytes}});
      j["device_memory"] = slabs;
      j["device_memory_max_bytes"] = gpu_peak;
    }
    std::printf("%s\n", j.dump(2).c_str());
  } else {
    std::printf("case            %s (%dD, %s)\n", c.name.c_str(), c.dim, c.file.c_str());
    std::printf("particles       %lld fluid, %lld wall, %lld total\n", static_cast<long long>(n.fluid),
                static_cast<long long>(n.wall), static_cast<long long>(n.total()));
    std::printf("resolution      dp = %g m, h = %g m (%.2f dp), support 2h\n", c.dp, P.h, c.smoothing_ratio);
    std::printf("sound speed     c0 = %g m/s (%s)\n", fluid.c0, c.fluids[0].sound_speed ? "from the case" : "automatic: 10 sqrt(g H)");
    if (c.sps)
      std::printf("turbulence      SPS (Smagorinsky C_s = %g, C_I = %g; filter width dp)\n", c.smagorinsky, c.sps_isotropic);
    std::printf("materials       %d (index: name, kind, properties)\n", static_cast<int>(P.materials.count));
    for (int m = 0; m < P.materials.count; ++m) {
      if (P.is_fluid(m)) {
        const FluidMaterial& f = P.materials.of(m);
        std::printf("  %-3d %-12s fluid: rho0 = %g kg/m3, mass = %g kg, mu = %g Pa s, c0 = %g m/s, gamma = %g, p_b = %g Pa\n", m,
                    names[m].c_str(), f.rho0, f.mass, f.viscosity, f.c0, f.gamma, f.background_pressure);
      } else {
        const int motion = P.materials.motion[m];
        const bool tank = m == P.materials.tank();
        const bool layers = tank ? c.tank_surface_particles : c.solids[static_cast<std::size_t>(m - P.materials.tank() - 1)].surface_particles;
        std::printf("  %-3d %-12s %s%s%s\n", m, names[m].c_str(), tank ? "tank walls" : "solid",
                    motion > 0 ? fmt::format(", moving (motion {})", motion - 1).c_str() : "",
                    layers ? ", wall particles in layers along its surface (wall_particles: surface)" : "");
      }
    }
    for_each_shape(c, [&](const std::string& owner, const Shape& s) {
      std::printf("shape           %s: %s; %s %g m%s\n", owner.c_str(), s.description.c_str(), c.dim == 2 ? "perimeter" : "surface",
                  s.area, c.dim == 2 ? "" : "2");
    });
    if (P.heat.on) {
      // Heat transfer: each material's thermal properties, the tank faces' conditions, the limit.
      std::printf("heat transfer   on: conduction limit dt <= %g s; buoyancy gravity (%g, %g, %g) m/s2\n",
                  heat_time_step(P, TimeStepControl{}), P.heat.gravity[0], P.heat.gravity[1], P.heat.gravity[2]);
      for (int m = 0; m < P.materials.count; ++m) {
        const ThermalMaterial& t = P.heat.material(static_cast<std::uint8_t>(m));
        std::printf("  %-3d %-12s k = %g W/(m K), c_p = %g J/(kg K)%s%s\n", m, names[m].c_str(), t.conductivity, t.specific_heat,
                    P.is_fluid(m) ? fmt::format(", beta = {:g} 1/K, T_ref = {:g} K", t.expansion, t.reference_temperature).c_str()
                                  : fmt::format(", rho = {:g} kg/m3", t.density).c_str(),
                    t.condition == ThermalCondition::Fixed ? ", held at its temperature" : "");
        if (P.is_fluid(m) && !c.fluids[m].thermal.viscosity.empty()) {
          std::string rows;
          for (const auto& [T, mu] : c.fluids[m].thermal.viscosity) rows += fmt::format(" ({:g} K, {:g})", T, mu);
          std::printf("      viscosity from its table [Pa s], linear between:%s\n", rows.c_str());
        }
      }
      const char* kinds[] = {"conducting", "held", "temperature", "heat flux", "adiabatic"};
      for (int f = 0; f < 2 * c.dim; ++f) {
        if (tank_wall_missing(c, f)) continue;  // periodic, the open top
        const FaceCondition& fc = P.heat.face[f];
        std::printf("  face %c%c        %s", "xyz"[f / 2], f % 2 ? '+' : '-', kinds[static_cast<int>(fc.kind)]);
        if (fc.kind == ThermalCondition::FaceTemperature) std::printf(" %g K", fc.value);
        if (fc.kind == ThermalCondition::FaceFlux) std::printf(" %g W/m2 into the fluid", fc.value);
        std::printf("\n");
      }
    }
    if (!c.motions.empty()) std::printf("motions         %zu\n", c.motions.size());
    for (std::size_t k = 0; k < c.motions.size(); ++k) {
      const MotionSpec& ms = c.motions[k];
      std::string what;
      if (ms.floating >= 0) {
        const BodySpec& b = c.bodies[ms.floating];
        const char* dofs[6] = {"x", "y", "z", "rx", "ry", "rz"};
        std::string free;
        for (int f = 0; f < 6; ++f)
          if (b.free[f]) free += std::string(free.empty() ? "" : ", ") + dofs[f];
        // Its number among the floating solids and its springs' numbers: the steering parameters
        // hinge_* and spring_* name them so (docs/live.md).
        int first_spring = 0;
        for (int o = 0; o < ms.floating; ++o) first_spring += static_cast<int>(c.bodies[o].springs.size());
        what = fmt::format("floating solid {}, ", ms.floating);
        what += c.dim == 2 ? fmt::format("mass {:g} kg/m, centre of mass [{:g}, {:g}], Izz {:g} kg m", b.mass, b.centre_of_mass[0],
                                         b.centre_of_mass[1], b.inertia[2])
                           : fmt::format("mass {:g} kg, centre of mass [{:g}, {:g}, {:g}], inertia [{:g}, {:g}, {:g}, {:g}, {:g}, {:g}] kg m2",
                                         b.mass, b.centre_of_mass[0], b.centre_of_mass[1], b.centre_of_mass[2], b.inertia[0], b.inertia[1],
                                         b.inertia[2], b.inertia[3], b.inertia[4], b.inertia[5]);
        if (b.hinge.on)
          what += fmt::format(", hinge at [{:g}, {:g}, {:g}] (stiffness {:g}, damping {:g})", b.hinge.point[0], b.hinge.point[1],
                              b.hinge.point[2], b.hinge.stiffness, b.hinge.damping);
        else
          what += ", free: " + free;
        if (!b.springs.empty())
          what += fmt::format(", springs {}-{}", first_spring, first_spring + static_cast<int>(b.springs.size()) - 1);
        what += b.contact.on ? fmt::format(", contact (penetration {:g} m, friction {:g})", b.contact.penetration, b.contact.friction)
                             : ", no contact";
        std::printf("  %-3zu %-12s %s\n", k, ms.body.c_str(), what.c_str());
        continue;
      }
      if (ms.sinusoid()) {
        what = fmt::format("sinusoid, period {:g} s", 2.0 * std::numbers::pi / ms.omega);
        if (ms.translation[0] != 0 || ms.translation[1] != 0 || ms.translation[2] != 0)
          what += c.dim == 2 ? fmt::format(", translation amplitude [{:g}, {:g}] m", ms.translation[0], ms.translation[1])
                             : fmt::format(", translation amplitude [{:g}, {:g}, {:g}] m", ms.translation[0], ms.translation[1], ms.translation[2]);
        if (ms.rotation != 0) what += fmt::format(", rotation amplitude {:g} deg", ms.rotation * 180.0 / std::numbers::pi);
      } else {
        what = fmt::format("time series {} ({} samples, t = {:g} to {:g} s)", ms.file, ms.times.size(), ms.times.front(), ms.times.back());
      }
      if (ms.rotation != 0 || !ms.sinusoid())
        what += c.dim == 2 ? fmt::format(" about [{:g}, {:g}]", ms.centre[0], ms.centre[1])
                           : fmt::format(" about [{:g}, {:g}, {:g}], axis [{:g}, {:g}, {:g}]", ms.centre[0], ms.centre[1], ms.centre[2],
                                         ms.axis[0], ms.axis[1], ms.axis[2]);
      if (ms.ramp > 0) what += fmt::format(", ramp {:g} s", ms.ramp);
      if (ms.end) what += fmt::format(", ends at {:g} s (over {:g} s)", *ms.end, ms.end_ramp);
      std::printf("  %-3zu %-12s %s\n", k, ms.body.c_str(), what.c_str());
    }
    if (c.drive.on) {
      std::string target;
      for (int k = 0; k < c.dim; ++k) target += fmt::format("{}{:g}", k ? ", " : "", c.drive.mean_velocity[k]);
      std::printf("drive           mean velocity [%s] m/s along the periodic axes, response time %g s\n", target.c_str(),
                  c.drive.response_time);
    }
    std::printf("time step       %g s (%s)\n", dt, c.fixed_dt ? "fixed" : "adaptive, initial CFL estimate");
    std::printf("cell lattice    %d x %d x %d\n", L.cells[0], L.cells[1], L.cells[2]);
    std::printf("memory          %zu bytes/particle, %.1f MiB for the particles (%s backend)\n", bpp, memory / 1048576.0,
                a.backend.c_str());
    std::printf("run memory      about %s at the peak; %s available (%s)%s\n", format_bytes(static_cast<double>(run_memory.bytes)).c_str(),
                format_bytes(static_cast<double>(available.bytes)).c_str(), available.source.c_str(),
                run_memory.bytes <= available.bytes ? "" : ": spate run refuses it");
    if (a.backend == "cuda") {
      std::printf("device memory   %zu bytes/particle slot; per GPU with --devices %d: at most %.1f MiB (%.0f bytes per owned particle)\n",
                  gpu::device_footprint(c.dim).per_particle(), a.devices, gpu_peak / 1048576.0,
                  per_gpu.empty() || per_gpu[0].owned == 0 ? 0.0 : static_cast<double>(per_gpu[0].bytes) / per_gpu[0].owned);
      for (auto& m : per_gpu)
        std::printf("  GPU %-3d       %lld owned + %lld ghosts, %zu slots, %.1f MiB\n", m.slab, static_cast<long long>(m.owned),
                    static_cast<long long>(m.ghosts), m.capacity, m.bytes / 1048576.0);
    }
  }
  return 0;
}

int compare_command(const CompareArgs& a) {
  if (!(a.tolerance >= 0)) throw BadInput(fmt::format("--tolerance {}: must be >= 0", a.tolerance));
  if (a.scaled_tolerance && !(*a.scaled_tolerance >= 0))
    throw BadInput(fmt::format("--scaled-tolerance {}: must be >= 0", *a.scaled_tolerance));
  // A heat run's checkpoints hold its temperatures: compare them too (the optional fields of the
  // case the first checkpoint ran, read once without them to learn which).
  std::uint16_t groups = 0;
  try {
    ParticleStore first;
    const CheckpointMeta m = read_checkpoint(a.a, first);
    if (!m.case_yaml.empty()) groups = optional_field_groups(physics_params(parse_case(m.case_yaml, a.a + " (its stored case)")));
  } catch (const std::exception& e) {
    throw BadInput(e.what());
  }
  const OptionalFields optional_fields(FieldGroups{static_cast<std::uint16_t>(groups & kThermal)});
  ParticleStore pa, pb;
  CheckpointMeta ma, mb;
  try {
    ma = read_checkpoint(a.a, pa);
    mb = read_checkpoint(a.b, pb);
  } catch (const std::exception& e) {
    throw BadInput(e.what());
  }
  if (pa.size() != pb.size() || pa.dim() != pb.dim()) {
    std::printf("different particle sets: %zu (%dD) vs %zu (%dD)\n", pa.size(), pa.dim(), pb.size(), pb.dim());
    return 1;
  }
  if (pa.id != pb.id) {
    std::printf("different particle ids\n");
    return 1;
  }
  // With --scaled-tolerance each field allows that fraction of its scale, from the case the first
  // checkpoint ran (its physics: dp, h, c0, rho0), or --tolerance where that is larger.
  std::optional<PhysicsParams> P;
  if (a.scaled_tolerance) {
    try {
      P = physics_params(parse_case(ma.case_yaml, a.a + " (its stored case)"));
    } catch (const std::exception& e) {
      throw BadInput(e.what());
    }
  }
  bool ok = true;
  if (P) std::printf("%-18s %-14s %-10s %s\n", "field", "max |a - b|", "at id", "tolerance");
  else std::printf("%-18s %-14s %s\n", "field", "max |a - b|", "at id");
  auto fa = pa.fields(), fb = pb.fields();
  for (std::size_t f = 0; f < fa.size(); ++f) {
    if (!fa[f].has(kCheckpointed) || fa[f].name == "id") continue;
    double worst = 0.0;
    std::uint32_t at = 0;
    const FieldType type = fa[f].spec->type;
    auto value = [type](const FieldRef& r, std::size_t i) -> double {
      if (type == FieldType::U8) return static_cast<unsigned char>(r.bytes()[i]);
      if (type == FieldType::U32) return reinterpret_cast<const std::uint32_t*>(r.bytes())[i];
      return reinterpret_cast<const float*>(r.bytes())[i];
    };
    for (std::size_t i = 0; i < pa.size(); ++i) {
      const double x = value(fa[f], i), y = value(fb[f], i);
      const double d = (std::isnan(x) != std::isnan(y)) ? INFINITY : (std::isnan(x) ? 0.0 : std::fabs(x - y));
      if (d > worst) worst = d, at = pa.id[i];
    }
    const double tolerance = P ? std::max(a.tolerance, *a.scaled_tolerance * field_scale(fa[f].name, *P)) : a.tolerance;
    ok = ok && worst <= tolerance;
    if (P) std::printf("%-18s %-14.6g %-10u %.3g\n", std::string(fa[f].name).c_str(), worst, at, tolerance);
    else std::printf("%-18s %-14.6g %u\n", std::string(fa[f].name).c_str(), worst, at);
  }
  std::printf("step %lld vs %lld, time %.17g vs %.17g\n", static_cast<long long>(ma.step), static_cast<long long>(mb.step),
              ma.time, mb.time);
  if (P) std::printf("%s (tolerance %g of each field's scale)\n", ok ? "MATCH" : "DIFFERENT", *a.scaled_tolerance);
  else std::printf("%s (tolerance %g)\n", ok ? "MATCH" : "DIFFERENT", a.tolerance);
  return ok ? 0 : 1;
}

namespace {
// The processor's model name (Linux: /proc/cpuinfo), "unknown" elsewhere.
std::string cpu_model() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("model name", 0) == 0) {
      const auto colon = line.find(':');
      if (colon != std::string::npos) return line.substr(line.find_first_not_of(" \t", colon + 1));
    }
  return "unknown";
}
}  // namespace

void check_environment() {
  try {
    pass_timers_enabled();
    gpu::per_thread_pair_loop(std::getenv("SPATE_GPU_PAIR_LOOP"));
    gpu::staged_links_forced(std::getenv("SPATE_CUDA_HALO_LINK"));
  } catch (const std::invalid_argument& e) {
    throw BadInput(std::string("environment: ") + e.what());
  }
}

int bench_command(const BenchArgs& a) {
  std::vector<std::string> overrides = a.overrides;
  overrides.push_back("output.interval=0");
  overrides.push_back("probes=[]");
  Case c = load(a.case_file, overrides);
  if (a.steps < 1) throw BadInput(fmt::format("--steps {}: must be >= 1", a.steps));
  check_backend(a.backend);
  if (a.pass_times) ::setenv("SPATE_PASS_TIMERS", "1", 1);
  // Neighbour interactions per step at the initial state: every pair inside the support that the
  // step's neighbour passes evaluate (fluid rates, wall state, summation density if enabled).
  cpu::InteractionCounts interactions;
  {
    InProcessHub hub(1);
    auto t = hub.endpoint(0, false);
    const Lattice L = make_lattice(c);
    const PhysicsParams P = physics_params(c);
    // The run's optional fields, so that the passes find what they read (heat's temperature).
    const OptionalFields optional_fields(FieldGroups{optional_field_groups(P)});
    SlabWorker w(L, P, *t);
    w.take_share(generate_particles(c), SlabLayout::uniform(L.cells[0], 1));
    w.prepare(false);
    interactions = cpu::count_interactions(w.particles(), w.grid(), w.params());
  }
  RunOptions o;
  o.out_dir = std::filesystem::temp_directory_path() / fmt::format("spate-bench-{}", ::getpid());
  o.steps = a.steps;
  o.threads = a.threads;
  o.devices = a.devices;
  o.backend = a.backend;
  o.quiet = true;
  RunResult r;
  try {
    r = Simulation(c, o).run();
  } catch (const InputError& e) {
    throw BadInput(e.what());
  }
  std::error_code ec;
  std::filesystem::remove_all(o.out_dir, ec);
  // A run that did not get through its steps has no rates to report.
  if (r.exit_code != 0) {
    if (process_group().rank == 0) spdlog::error("{}", r.message);
    return r.exit_code;
  }
  if (process_group().rank != 0) return 0;
  // Rates from the time loop alone: the final checkpoint every run writes is not stepping.
  const double seconds = r.stepping_seconds > 0 ? r.stepping_seconds : r.wall_seconds;
  const double psps = r.steps * static_cast<double>(r.particles.total()) / seconds;
  const double per_step = r.steps / seconds;
  const double ips = per_step * static_cast<double>(interactions.total());
  const double fluid_ips = per_step * static_cast<double>(interactions.fluid);
  const int threads = a.threads > 0 ? a.threads : hardware_threads();
  if (a.json) {
    nlohmann::ordered_json j;
    j["case"] = c.name;
    j["particles"] = {{"fluid", r.particles.fluid}, {"wall", r.particles.wall}, {"total", r.particles.total()}};
    j["threads"] = threads;
    j["devices"] = a.devices;
    j["backend"] = a.backend;
    j["ranks"] = process_group().ranks;
    j["steps"] = r.steps;
    j["wall_seconds"] = r.wall_seconds;
    j["stepping_seconds"] = r.stepping_seconds;
    j["seconds_per_step"] = seconds / r.steps;
    j["particle_steps_per_second"] = psps;
    j["interactions_per_step"] = interactions.total();
    j["interactions_per_second"] = ips;
    j["fluid_interactions_per_step"] = interactions.fluid;
    j["fluid_interactions_per_second"] = fluid_ips;
    j["wall_interactions_per_step"] = interactions.wall;
    j["summation_interactions_per_step"] = interactions.summation;
    j["bytes_per_particle"] = r.bytes_per_particle;
    j["ghost_particles"] = r.ghosts;
    // What the CPU code was built for and runs on (docs/performance.md's tables name both).
    const cpu::BuildTarget target = cpu::build_target();
    j["cpu"] = {{"model", cpu_model()},
                {"isa", target.isa},
                {"vector_bits", target.vector_bits},
                {"arch_flags", target.flags},
                {"pair_loop", cpu::pair_loop_vectorised(physics_params(c)) ? "vector" : "scalar"}};
    // Decomposition diagnostics (as in summary.json): per-slab loop seconds and the balancer's work.
    j["device_particles"] = r.slab_particles;
    j["device_busy_seconds"] = r.slab_busy_seconds;
    j["imbalance_history"] = r.imbalance_history;
    j["face_moves"] = r.face_moves;
    // Per device, the seconds of each pass over the whole run (SPATE_PASS_TIMERS=1 or --pass-times;
    // backend/pass_times.hpp), passes that never ran left out.
    if (!r.slab_pass_seconds.empty()) {
      nlohmann::ordered_json passes = nlohmann::ordered_json::array();
      for (const PassSeconds& slab : r.slab_pass_seconds) {
        nlohmann::ordered_json one = nlohmann::ordered_json::object();
        for (int k = 0; k < kPassCount; ++k)
          if (slab[k] > 0.0) one[kPassNames[k]] = slab[k];
        passes.push_back(one);
      }
      j["pass_seconds"] = passes;
    }
    std::printf("%s\n", j.dump(2).c_str());
  } else {
    std::printf("%s: %lld particles, %d threads, %d devices: %.4f s/step, %.3g particle-steps/s, %.3g interactions/s "
                "(fluid %.3g), %.1f B/particle; CPU code %s, %s pair loop\n",
                c.name.c_str(), static_cast<long long>(r.particles.total()), threads, a.devices, seconds / r.steps, psps,
                ips, fluid_ips, r.bytes_per_particle, cpu::build_target().isa,
                cpu::pair_loop_vectorised(physics_params(c)) ? "vector" : "scalar");
    for (std::size_t d = 0; d < r.slab_pass_seconds.size(); ++d) {
      std::printf("device %zu passes (s over %lld steps):", d, static_cast<long long>(r.steps));
      for (int k = 0; k < kPassCount; ++k)
        if (r.slab_pass_seconds[d][k] > 0.0) std::printf(" %s %.4g", kPassNames[k], r.slab_pass_seconds[d][k]);
      std::printf("\n");
    }
  }
  return 0;
}

}  // namespace spate::app
