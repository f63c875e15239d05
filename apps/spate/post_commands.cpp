// After the run: spate post (probes and Catalyst pipelines on saved snapshots or checkpoints) and
// spate plot (PNG plots of the probes, by scripts/plot_probes.py); spate growth (an instability's
// growth rate from a probe's amplitude, sim/growth.hpp).
#include <fmt/format.h>
#include <fcntl.h>
#include <spawn.h>
#include <spdlog/spdlog.h>
#include <sys/wait.h>

#include <algorithm>
#include <cstdlib>
#include <optional>
#include <omp.h>

#include "commands.hpp"
#include "sim/growth.hpp"
#include "sim/insitu.hpp"
#include "sim/post.hpp"
#ifdef SPATE_WITH_CATALYST
#include "catalyst_sink.hpp"
#endif

extern char** environ;

namespace spate::app {

namespace {

// Starts argv (searched on the PATH), its output to /dev/null unless `quiet` is false; its exit
// status, or -1 when it could not start.
int spawn_and_wait(const std::vector<std::string>& args, bool quiet) {
  std::vector<const char*> argv;
  for (auto& a : args) argv.push_back(a.c_str());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  if (quiet) {
    posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
    posix_spawn_file_actions_addopen(&actions, 2, "/dev/null", O_WRONLY, 0);
  }
  pid_t pid = 0;
  const int started = posix_spawnp(&pid, argv[0], &actions, nullptr, const_cast<char* const*>(argv.data()), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (started != 0) return -1;
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
}

// The Python that has matplotlib: $SPATE_PYTHON as given; else the first of the one CMake found,
// the system's /usr/bin/python3 and python3 on the PATH that imports matplotlib. A pyenv or venv
// Python first on the PATH often lacks the Debian package python3-matplotlib, which only the
// system's interpreter sees; if none has it, the first that exists reports the missing module.
std::string python() {
  const char* env = std::getenv("SPATE_PYTHON");
  if (env && *env) return env;
  std::vector<std::string> candidates;
#ifdef SPATE_PYTHON
  candidates.push_back(SPATE_PYTHON);
#endif
  candidates.insert(candidates.end(), {"/usr/bin/python3", "python3"});
  for (const auto& c : candidates)
    if (spawn_and_wait({c, "-c", "import matplotlib"}, true) == 0) return c;
  return candidates.front();
}

// Plots DIR/probes/*.csv into `out`, titled with the case's name and each probe's description;
// the script's exit status (0, 2 bad input; else 4).
int plot_probes(const std::filesystem::path& dir, const std::filesystem::path& out, const std::string& title, const Case* c) {
  const std::string interpreter = python(), script = (data_dir() / "scripts" / "plot_probes.py").string();
  const std::string probes = (dir / "probes").string(), target = out.string();
  std::vector<std::string> args = {interpreter, script, probes, target, "--title", title};
  if (c)
    for (const ProbeSpec& p : c->probes) args.insert(args.end(), {"--describe", p.name + "=" + probe_description(p, c->dim)});
  spdlog::debug("plotting with {} {}", interpreter, script);
  const int status = spawn_and_wait(args, false);
  if (status < 0)
    throw BadInput(fmt::format("spate plot: cannot start {} (set SPATE_PYTHON to a Python 3 with matplotlib)", interpreter));
  const int code = status == 128 ? 4 : status;
  if (code == 0) spdlog::info("plots of {} in {}", probes, target);
  return code == 0 || code == 2 ? code : 4;
}

// The case of a folder, or of the run folder around a post output folder; none if neither has one.
std::optional<Case> case_of(const std::filesystem::path& dir) {
  const auto full = std::filesystem::absolute(dir).lexically_normal();
  for (const auto& d : {full, full.parent_path()}) {
    try {
      return run_case(d);
    } catch (const std::exception&) {
    }
  }
  return std::nullopt;
}

}  // namespace

int post_command(const PostArgs& a) {
  const std::filesystem::path run_dir(a.run_dir);
  if (!std::filesystem::is_directory(run_dir)) throw BadInput(fmt::format("{}: no such run folder", a.run_dir));
  // --probe definitions replace the case's probes; the case loader checks them like a case file's.
  std::vector<std::string> overrides;
  if (!a.probes.empty()) {
    std::string list;
    for (auto& p : a.probes) list += (list.empty() ? "" : ", ") + p;
    overrides.push_back("probes=[" + list + "]");
  }
  Case c;
  try {
    c = run_case(run_dir);
  } catch (const CaseError& e) {
    throw BadInput(e.what());
  }
  try {
    if (!overrides.empty()) c = run_case(run_dir, overrides);
  } catch (const CaseError& e) {
    throw BadInput(fmt::format("--probe: {}", e.what()));
  }
#ifndef SPATE_WITH_CATALYST
  if (!a.pipelines.empty()) throw BadInput("--pipeline: this spate was built without ParaView Catalyst");
#endif
  if (c.probes.empty() && a.pipelines.empty())
    throw BadInput(fmt::format("{}: nothing to do: the case has no probes (define some with --probe) and no --pipeline is given", a.run_dir));
  if (a.threads < 0) throw BadInput(fmt::format("--threads {}: must be >= 0 (0: all cores)", a.threads));

  // The saved steps: snapshots when the run wrote any, else checkpoints (or as --from says).
  if (!a.from.empty() && a.from != "snapshots" && a.from != "checkpoints")
    throw BadInput(fmt::format("--from {}: expected 'snapshots' or 'checkpoints'", a.from));
  SavedKind kind = a.from == "checkpoints" ? SavedKind::Checkpoint : SavedKind::Snapshot;
  std::vector<SavedStep> steps = saved_steps(run_dir, kind);
  if (a.from.empty() && steps.empty()) steps = saved_steps(run_dir, kind = SavedKind::Checkpoint);
  const char* what = kind == SavedKind::Snapshot ? "snapshots (particles.pvd)" : "checkpoints (checkpoints/*.h5)";
  if (!a.steps.empty()) {
    std::vector<SavedStep> chosen;
    for (long long s : a.steps) {
      auto it = std::find_if(steps.begin(), steps.end(), [&](const SavedStep& x) { return x.step == s; });
      if (it == steps.end()) throw BadInput(fmt::format("--step {}: {} has no saved step {} among its {}", s, a.run_dir, s, what));
      chosen.push_back(*it);
    }
    steps = chosen;
  }
  if (steps.empty()) throw BadInput(fmt::format("{}: no saved {}", a.run_dir, what));

  const std::filesystem::path out = a.out.empty() ? run_dir / "post" : std::filesystem::path(a.out);
  omp_set_num_threads(a.threads > 0 ? a.threads : hardware_threads());
  // The saved particles as the run had them: its optional fields (the temperature of a heat run).
  const OptionalFields optional_fields(FieldGroups{optional_field_groups(physics_params(c))});
  std::unique_ptr<SavedProbes> probes;
  if (!c.probes.empty()) {
    // The run's steering, so that steered wall motions are replayed (probes that follow a body).
    std::vector<SteeringChange> steering;
    const auto log = run_dir / "steering.log";
    try {
      if (std::filesystem::exists(log)) steering = read_log(log.string(), c.dim);
      probes = std::make_unique<SavedProbes>(c, out, steering);
    } catch (const std::runtime_error& e) {
      throw BadInput(fmt::format("{}: {}", log.string(), e.what()));
    }
  }
#ifdef SPATE_WITH_CATALYST
  std::unique_ptr<catalyst::CatalystSink> pipelines;
  if (!a.pipelines.empty()) {
    catalyst::CatalystOptions co;
    co.scripts.assign(a.pipelines.begin(), a.pipelines.end());
    co.working_dir = out;
    pipelines = make_catalyst_sink(std::move(co), c);
  }
#endif
  bool warned = false;
  for (const SavedStep& s : steps) {
    SavedState state;
    try {
      state = load_saved(s, c.dim);
    } catch (const std::exception& e) {
      throw BadInput(e.what());
    }
    if (!state.derived_saved && !warned) {
      spdlog::warn("{}: written before checkpoints kept the pressures; they are recomputed from the densities (close to the run's "
                   "values, not equal)", s.file.string());
      warned = true;
    }
    if (probes) probes->sample(state);
#ifdef SPATE_WITH_CATALYST
    if (pipelines) {
      std::vector<SlabView> views;
      for (std::size_t k = 0; k < state.pieces.size(); ++k) views.push_back(slab_view(state.pieces[k], state.slabs[k], state.slab_count, static_cast<int>(c.fluids.size())));
      pipelines->execute(state.step, state.time, views);
    }
#endif
    spdlog::debug("post: step {} (t = {:.6g} s) from {}", state.step, state.time, s.file.string());
  }
  std::string failures;
#ifdef SPATE_WITH_CATALYST
  if (pipelines)
    for (auto& f : pipelines->failures()) failures += "\n" + f;
#endif
  spdlog::info("post: {} saved steps of {} ({}): {}{}", steps.size(), c.name, kind == SavedKind::Snapshot ? "snapshots" : "checkpoints",
               probes ? fmt::format("{} probes in {}", c.probes.size(), (out / "probes").string()) : std::string("no probes"),
               a.pipelines.empty() ? std::string() : fmt::format("; pipeline extracts in {}", (out / "insitu").string()));
  if (a.plot && probes) {
    const int code = plot_probes(out, out / "plots", c.name, &c);
    if (code != 0) return code;
  }
  // A script that fails on a later step was switched off while the rest went on; it is still the
  // input that failed.
  if (!failures.empty()) throw BadInput("a pipeline failed and was switched off:" + failures);
  return 0;
}

int plot_command(const PlotArgs& a) {
  const std::filesystem::path dir(a.dir);
  if (!std::filesystem::is_directory(dir / "probes"))
    throw BadInput(fmt::format("{}: no probes/ folder (a run folder, or a spate post output folder)", a.dir));
  const std::optional<Case> c = case_of(dir);
  const std::string title = c ? c->name : std::filesystem::absolute(dir).lexically_normal().filename().string();
  return plot_probes(dir, a.out.empty() ? dir / "plots" : std::filesystem::path(a.out), title, c ? &*c : nullptr);
}

int growth_command(const GrowthArgs& a) {
  std::vector<std::pair<double, double>> samples;
  try {
    samples = read_probe_column(a.csv, a.column);
  } catch (const std::runtime_error& e) {
    throw BadInput(e.what());
  }
  // The linear range by default: up to five times the first amplitude.
  double until = a.until.value_or(0.0);
  if (!a.until) {
    for (auto [t, v] : samples)
      if (v > 0) {
        until = 5.0 * v;
        break;
      }
  }
  if (!(until > 0)) throw BadInput(fmt::format("--until {}: must be > 0", until));
  GrowthFit fit;
  try {
    fit = fit_growth(samples, until);
  } catch (const std::invalid_argument& e) {
    throw BadInput(fmt::format("{}: column '{}': {}", a.csv, a.column, e.what()));
  }
  if (a.json)
    fmt::print("{{\"rate\": {:.9g}, \"growing\": {:.9g}, \"decaying\": {:.9g}, \"from\": {:.9g}, \"to\": {:.9g}, \"samples\": {}, "
               "\"rms\": {:.6g}, \"until\": {:.9g}}}\n",
               fit.rate, fit.growing, fit.decaying, fit.from, fit.to, fit.samples, fit.rms, until);
  else
    fmt::print("growth rate n = {:.6g} 1/s: {} = {:.4g} e^(n t) + {:.4g} e^(-n t) over t = {:.4g} to {:.4g} s ({} samples, "
               "rms error {:.2g}%)\n",
               fit.rate, a.column, fit.growing, fit.decaying, fit.from, fit.to, fit.samples, 100.0 * fit.rms);
  return 0;
}

}  // namespace spate::app
