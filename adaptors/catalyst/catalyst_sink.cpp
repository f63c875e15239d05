#include "catalyst_sink.hpp"

#ifdef SPATE_CATALYST_MPI
#include <mpi.h>
#endif

#include <unistd.h>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <set>
#include <string_view>

#include "extract_index.hpp"
#include "helper_process.hpp"
#include "insitu_wire.hpp"
#include "particles/particle_store.hpp"
#include "private_display.hpp"

namespace spate::catalyst {

namespace {

bool mpi_initialised() {
#ifdef SPATE_CATALYST_MPI
  int on = 0;
  MPI_Initialized(&on);
  return on != 0;
#else
  return false;
#endif
}

int mpi_rank() {
#ifdef SPATE_CATALYST_MPI
  int rank = 0;
  if (mpi_initialised()) MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  return rank;
#else
  return 0;
#endif
}

// mpirun (or another PMIx launcher) started this process: its MPI settings are the launcher's.
bool started_by_mpi_launcher() { return std::getenv("OMPI_COMM_WORLD_SIZE") || std::getenv("PMIX_RANK"); }

// ParaView initialises MPI wherever Catalyst runs. Outside mpirun, OpenMPI would then start a
// singleton `orted` daemon that listens on every interface, and its TCP transport would listen too
// (ports 1024 and up), for the whole run. One process needs neither: no daemon (it only serves
// MPI_Comm_spawn) and shared memory only; with both, spate and its children open no listening
// socket at all (docs/live.md, Security). Explicit settings in the environment win.
void quiet_mpi_environment() {
  if (started_by_mpi_launcher()) return;
  setenv("OMPI_MCA_btl", "self,vader", 0);
  setenv("OMPI_MCA_ess_singleton_isolated", "1", 0);
}

// OpenMPI 4 singletons of one user on one node share a session directory, <tmp>/ompi.<host>.<uid>:
// a process that finalises removes it once it looks empty, and one that is starting at that moment
// cannot create its own entry in it, so its MPI_Init fails ("orte_session_dir failed";
// open-mpi/ompi#8510). Runs started together on one node (a job array, a test suite) hit it now and
// then, and the helper could not start. Each run's helpers get a session directory of their own,
// removed after the last helper has ended. An explicit OMPI_MCA_orte_tmpdir_base, or mpirun's
// environment, wins; where no directory can be made, OpenMPI's default stays.
class PrivateMpiSessionDir {
 public:
  PrivateMpiSessionDir() {
    static const bool chosen_outside = std::getenv("OMPI_MCA_orte_tmpdir_base") != nullptr;
    if (chosen_outside || started_by_mpi_launcher()) return;
    const char* tmp = std::getenv("TMPDIR");
    std::string pattern = std::string(tmp && *tmp ? tmp : "/tmp") + "/spate-mpi.XXXXXX";
    if (!mkdtemp(pattern.data())) return;
    dir_ = pattern;
    setenv("OMPI_MCA_orte_tmpdir_base", dir_.c_str(), 1);
  }
  ~PrivateMpiSessionDir() {
    std::error_code ec;
    if (!dir_.empty()) std::filesystem::remove_all(dir_, ec);
  }
  PrivateMpiSessionDir(const PrivateMpiSessionDir&) = delete;
  PrivateMpiSessionDir& operator=(const PrivateMpiSessionDir&) = delete;

 private:
  std::string dir_;
};

// This very program, even if its file was replaced or deleted since it started (a rebuild during
// a run): the helper restarted in the middle of a run must be the same binary.
std::filesystem::path this_program() { return "/proc/self/exe"; }

}  // namespace

struct CatalystSink::Impl : ScriptObserver {
  struct Script {
    std::filesystem::path path;  // absolute
    std::string label;           // as the user gave it (or "--live HOST:PORT")
    bool live = false;
    bool active = true;
  };

  CatalystOptions options;
  std::vector<Script> scripts;  // by id: the options' scripts, then live.py
  bool isolated = true;
  std::unique_ptr<PrivateDisplay> display;
  std::unique_ptr<ExtractIndex> index;  // the writing process only (rank 0)
  // In process.
  std::unique_ptr<CatalystEngine> engine;
  std::unique_ptr<CatalystSteering> steering;
  // Isolated.
  const SharedParticleMemory* arena = nullptr;
  std::unique_ptr<PrivateMpiSessionDir> mpi_session;  // outlives every helper
  std::unique_ptr<HelperProcess> helper;
  std::vector<SteeringChange> requested;  // from the helper, until polled
  int display_restarts = 0, stray_deaths = 0;
  std::vector<FieldVector<char>> staging;  // particle memory, so in the arena
  bool warned_staging = false;
  // The step being run.
  std::int64_t step = 0;
  double time = 0.0;
  int current = -1;       // the script that started last and has not finished
  std::set<int> done;     // scripts done with this step
  std::vector<std::string> load_errors;
  // Results.
  std::vector<std::string> failures, incidents;
  InSituTiming timing;
  bool first = true;
  std::int64_t steps_done = 0;
  std::atomic<int> every{1};
  mutable std::mutex mutex;  // guards failures, incidents, timing (read from other threads)

  struct HelperSteering : SteeringSource {
    Impl* m;
    explicit HelperSteering(Impl* impl) : m(impl) {}
    std::vector<SteeringChange> poll(std::int64_t step, double time) override {
      auto out = std::move(m->requested);
      m->requested.clear();
      for (auto& c : out) c.step = step, c.time = time;
      return out;
    }
  } helper_steering{this};

  bool has_live() const { return options.live.has_value(); }
  int live_id() const { return has_live() ? static_cast<int>(scripts.size()) - 1 : -1; }
  bool any_active() const {
    for (auto& s : scripts)
      if (s.active) return true;
    return false;
  }

  // ScriptObserver: which script runs, and which files it wrote.
  void started(int id) override { current = id; }
  void finished(int id) override {
    done.insert(id);
    current = -1;
    if (index) index->record(step, time, scripts[id].label);
  }

  // Records an event; the log gets its first line (a traceback is in the log already).
  void note(std::vector<std::string>& list, std::string text) {
    spdlog::warn("in situ: {}", text.substr(0, text.find('\n')));
    std::lock_guard lock(mutex);
    list.push_back(std::move(text));
  }

  // A script is out for the rest of the run; in the run's first in-situ step that is a load error.
  // `what` says what happened, `detail` (a traceback) follows on the next lines.
  void switch_off(int id, const std::string& what, const std::string& detail = "") {
    Script& s = scripts[id];
    if (!s.active) return;
    s.active = false;
    if (steps_done == 0 && !s.live) {
      load_errors.push_back(fmt::format("--pipeline {}: the script failed to load: {}{}{}", s.label, what,
                                        detail.empty() ? "" : ":\n", detail));
      return;
    }
    note(failures, fmt::format("{}: {} at step {} (t = {:.6g} s), switched off{}{}{}", s.label, what, step, time,
                               s.live ? " (the run goes on without live)" : "", detail.empty() ? "" : ":\n", detail));
  }

  void account(const nlohmann::json& script_seconds, double adaptor_seconds, bool ran) {
    std::lock_guard lock(mutex);
    timing.steps += 1;
    timing.adaptor_seconds += adaptor_seconds;
    timing.adaptor_step_seconds.push_back(ran ? adaptor_seconds : 0.0);
    timing.pipelines_step_seconds.push_back(0.0);
    for (auto& entry : script_seconds) {
      const int id = entry.at(0).get<int>();
      const double s = entry.at(1).get<double>();
      timing.pipelines_seconds += s;
      timing.pipelines_step_seconds.back() += s;
      if (id >= 0 && static_cast<std::size_t>(id) < timing.script_seconds.size()) timing.script_seconds[id] += s;
    }
  }

  void python_failures(const nlohmann::json& list) {
    for (auto& f : list) {
      const int id = f.at("id").get<int>();
      switch_off(id, "failed", f.at("error").get<std::string>());
    }
  }

  // ---- in process ----
  void start_in_process() {
    display = std::make_unique<PrivateDisplay>(/*export_display=*/true);
    EngineOptions eo;
    for (std::size_t k = 0; k < scripts.size(); ++k) {
      eo.scripts.push_back(scripts[k].path);
      eo.ids.push_back(static_cast<int>(k));
    }
    eo.working_dir = options.working_dir;
    eo.constants = options.constants;
    eo.mpi = mpi_initialised();
    engine = std::make_unique<CatalystEngine>(eo);
    if (has_live()) steering = std::make_unique<CatalystSteering>(options.live->xml, options.live->initial);
  }

  void run_in_process(const std::vector<SlabView>& slabs) {
    const EngineStep r = engine->run_step(step, time, slabs, {}, this);
    nlohmann::json seconds = nlohmann::json::array();
    for (auto& [id, s] : r.script_seconds) seconds.push_back({id, s});
    account(seconds, r.adaptor_seconds, r.ran);
    nlohmann::json fails = nlohmann::json::array();
    for (auto& f : r.failures) fails.push_back({{"id", f.id}, {"error", f.error}});
    python_failures(fails);
  }

  // ---- isolated ----
  nlohmann::json init_message() const {
    nlohmann::json j = {{"type", "init"}, {"working_dir", options.working_dir.string()}, {"log_level", static_cast<int>(spdlog::get_level())}};
    j["scripts"] = nlohmann::json::array();
    j["ids"] = nlohmann::json::array();
    for (std::size_t k = 0; k < scripts.size(); ++k) {
      if (!scripts[k].active) continue;
      j["scripts"].push_back(scripts[k].path.string());
      j["ids"].push_back(k);
    }
    j["constants"] = nlohmann::json::object();
    for (auto& [name, value] : options.constants) j["constants"][name] = value;
    j["arena"] = {{"base", arena->base}, {"size", arena->size}};
    j["live"] = nullptr;
    if (has_live() && scripts[live_id()].active) {
      const LiveOptions& l = *options.live;
      j["live"] = {{"id", live_id()},
                   {"url", l.url},
                   {"xml", l.xml.string()},
                   {"timeout", l.handshake_timeout},
                   {"initial",
                    {{"gravity", l.initial.gravity},
                     {"viscosity", l.initial.viscosity},
                     {"phase_viscosity", l.initial.phase_viscosity},
                     {"artificial_viscosity", l.initial.artificial_viscosity},
                     {"motion_amplitude", l.initial.motion_amplitude},
                     {"motion_frequency", l.initial.motion_frequency},
                     {"face_temperature", l.initial.face_temperature},
                     {"face_heat_flux", l.initial.face_heat_flux},
                     {"spring_stiffness", l.initial.spring_stiffness},
                     {"spring_damping", l.initial.spring_damping},
                     {"hinge_stiffness", l.initial.hinge_stiffness},
                     {"hinge_damping", l.initial.hinge_damping},
                     {"insitu_every", l.initial.insitu_every}}}};
    }
    return j;
  }

  // Starts a helper for the active scripts. At construction a failure is a load error; later it
  // switches in situ off for the rest of the run.
  bool start_helper() {
    std::string why;
    try {
      helper = std::make_unique<HelperProcess>(options.helper_program, display->display(), *arena);
      nlohmann::json reply;
      if (!helper->send(init_message())) {
        why = "it did not take its instructions (" + helper->reap(5.0) + ")";
      } else {
        const auto got = helper->receive(reply, std::max(120.0, options.timeout));
        if (got == wire::Received::kMessage && reply.value("type", "") == "ready") return true;
        if (got == wire::Received::kMessage && reply.value("type", "") == "error") why = reply.value("message", "");
        else if (got == wire::Received::kTimeout) why = "it did not start within the time allowed (" + helper->kill_now() + ")";
        else why = "it ended while starting (" + helper->reap(5.0) + ")";
      }
    } catch (const std::exception& e) {
      why = e.what();
    }
    helper.reset();
    if (steps_done == 0 && first) throw InSituLoadError("ParaView Catalyst could not start: " + why);
    for (std::size_t k = 0; k < scripts.size(); ++k)
      if (scripts[k].active) switch_off(static_cast<int>(k), "the in-situ process could not be restarted (" + why + ")");
    return false;
  }

  // The solver's arrays as the helper can see them: in the shared arena they go as they are (zero
  // copy); anything else (arrays allocated before the arena existed) is copied into it once per step.
  std::vector<SlabView> staged(const std::vector<SlabView>& slabs) {
    std::vector<SlabView> out = slabs;
    std::size_t used = 0;
    auto stage = [&](const void*& p, std::size_t bytes) {
      if (!p || bytes == 0 || arena->contains(p)) return;
      if (!warned_staging) {
        spdlog::warn("in situ: particle arrays outside the shared arena are copied for the pipelines");
        warned_staging = true;
      }
      if (staging.size() <= used) staging.emplace_back();
      auto& buffer = staging[used++];
      buffer.resize(bytes);
      std::memcpy(buffer.data(), p, bytes);
      p = buffer.data();
    };
    for (SlabView& v : out) {
      for (auto& p : v.pos) {
        const void* q = p;
        stage(q, v.owned * sizeof(float));
        p = static_cast<const float*>(q);
      }
      for (SlabArray& a : v.arrays)
        for (auto& d : a.data) stage(d, v.owned * field_type_size(a.type));
    }
    return out;
  }

  // The helper ended in the middle of a step: a lost display (replace it and retry), the live
  // handshake watch, or the script that was running (switched off).
  void after_helper_ended(const std::string& how, bool display_lost, const std::string& live_timeout) {
    if (!live_timeout.empty() && has_live()) {
      switch_off(live_id(), live_timeout);
      return;
    }
    if (display_lost || !display->alive()) {
      const std::string lost = display->display();
      if (display_restarts < 3 && display->restart()) {
        ++display_restarts;
        note(incidents, fmt::format("step {}: the display {} was lost (the in-situ process {}); the step is run again on a "
                                    "new private display {}", step, lost.empty() ? "(none)" : lost, how, display->display()));
        return;
      }
      if (current >= 0) switch_off(current, fmt::format("could not render: the display {} was lost and no new one could be started (the in-situ process {})", lost, how));
      return;
    }
    if (current >= 0) {
      switch_off(current, "ended the in-situ process (" + how + ")");
      return;
    }
    // Outside any script (ParaView itself): once is an incident, twice ends in situ.
    if (++stray_deaths < 2) {
      note(incidents, fmt::format("step {}: the in-situ process {} outside any pipeline; restarted", step, how));
      return;
    }
    for (std::size_t k = 0; k < scripts.size(); ++k)
      if (scripts[k].active) switch_off(static_cast<int>(k), "the in-situ process ended twice outside any pipeline (" + how + ")");
  }

  void run_isolated(const std::vector<SlabView>& slabs) {
    const nlohmann::json views = wire::slabs_to_json(staged(slabs));
    for (;;) {
      std::set<int> skip = done;
      bool left = false;
      for (std::size_t k = 0; k < scripts.size(); ++k) left = left || (scripts[k].active && !done.count(static_cast<int>(k)));
      if (!left) return;
      if (!helper && !start_helper()) return;
      current = -1;
      std::string live_timeout;
      if (helper->send({{"type", "step"}, {"step", step}, {"time", time}, {"slabs", views}, {"skip", skip}})) {
        for (;;) {
          // A script gets `timeout` seconds of silence; the live script may wait for ever (a paused
          // client), its handshake is watched inside the helper.
          const bool live_running = current >= 0 && scripts[current].live;
          nlohmann::json in;
          const auto got = helper->receive(in, live_running ? -1.0 : options.timeout);
          if (got == wire::Received::kTimeout) {
            const std::string how = helper->kill_now();
            helper.reset();
            if (index) index->discard();
            if (current >= 0) switch_off(current, fmt::format("did not finish within {:g} s (insitu.timeout) and was stopped", options.timeout));
            else after_helper_ended(how, false, "");
            break;
          }
          if (got == wire::Received::kClosed) break;
          const std::string type = in.value("type", "");
          if (type == "started") started(in.at("id").get<int>());
          else if (type == "finished") finished(in.at("id").get<int>());
          else if (type == "live_timeout") live_timeout = in.value("message", "");
          else if (type == "done") {
            account(in.at("script_seconds"), in.value("adaptor_seconds", 0.0), in.value("ran", false));
            python_failures(in.at("failures"));
            for (auto& c : in.at("steering")) {
              SteeringChange change{step, time, c.at("name").get<std::string>(), c.at("value").get<std::vector<double>>()};
              remember_steered(change);
              requested.push_back(std::move(change));
            }
            return;
          }
        }
      }
      if (helper) {  // the connection closed: the helper ended
        const std::string how = helper->reap(10.0);
        const bool display_lost = helper->exit_status() == kDisplayLostExit;
        helper.reset();
        if (index) index->discard();
        after_helper_ended(how, display_lost, live_timeout);
      }
    }
  }

  // A fresh helper's steering proxy starts with the values steered so far.
  void remember_steered(const SteeringChange& c) {
    if (!has_live() || validate(c, static_cast<int>(dimensions())).has_value()) return;
    options.live->initial.take(c);
  }
  double dimensions() const {
    for (auto& [name, value] : options.constants)
      if (name == "dimensions") return value;
    return 3.0;
  }
};

CatalystSink::CatalystSink(CatalystOptions options) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  if (options.every < 1) throw InSituLoadError(fmt::format("--insitu-every {}: must be at least 1", options.every));
  if (!(options.timeout > 0)) throw InSituLoadError(fmt::format("insitu.timeout {}: must be > 0 seconds", options.timeout));
  if (options.live) options.scripts.push_back(options.live->script);
  for (auto& script : options.scripts) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(script, ec) && !std::filesystem::is_directory(script, ec))
      throw InSituLoadError(fmt::format("--pipeline {}: no such script", script.string()));
    m.scripts.push_back({std::filesystem::absolute(script), script.string(), false, true});
  }
  if (options.live) {
    m.scripts.back().live = true;
    m.scripts.back().label = "--live " + options.live->url;
  }
  if (!options.working_dir.empty()) options.working_dir = std::filesystem::absolute(options.working_dir);
  if (options.helper_program.empty()) options.helper_program = this_program();
  m.every = options.every;
  m.timing.script_seconds.assign(m.scripts.size(), 0.0);
  m.options = std::move(options);
  quiet_mpi_environment();
  // SPATE_INSITU_IN_PROCESS=1 runs the pipelines in the solver's process (no isolation: for a
  // debugger, and to measure what the helper costs; docs/insitu.md).
  const char* in_process = std::getenv("SPATE_INSITU_IN_PROCESS");
  const bool asked_in_process = in_process && std::string_view(in_process) == "1";
  m.isolated = m.options.isolation == Isolation::kHelper ||
               (m.options.isolation == Isolation::kAuto && !mpi_initialised() && !asked_in_process);
  if (mpi_rank() == 0 && !m.options.working_dir.empty()) m.index = std::make_unique<ExtractIndex>(m.options.working_dir);
  if (!m.isolated) {
    m.start_in_process();
    return;
  }
  try {
    m.arena = &share_particle_memory();
  } catch (const std::exception& e) {
    throw InSituLoadError(e.what());
  }
  m.display = std::make_unique<PrivateDisplay>(/*export_display=*/false);
  m.mpi_session = std::make_unique<PrivateMpiSessionDir>();
  m.start_helper();
}

CatalystSink::~CatalystSink() {
  Impl& m = *impl_;
  if (m.index) {
    const std::string error = m.index->write(true);
    if (!error.empty()) spdlog::error("{}", error);
  }
  if (m.helper) {
    const std::string how = m.helper->finish(60.0);
    if (m.helper->exit_status() != 0) m.note(m.incidents, "the in-situ process " + how + " while finishing (after the last in-situ step)");
  }
  m.helper.reset();
  m.steering.reset();  // unregisters its proxy while ParaView is still up
  m.engine.reset();
}

bool CatalystSink::wants(std::int64_t step, double) {
  if (!impl_->any_active()) return false;
  return impl_->first || step % impl_->every.load() == 0;
}

void CatalystSink::set_interval(int every) {
  if (every >= 1) impl_->every.store(every);
}

void CatalystSink::execute(std::int64_t step, double time, const std::vector<SlabView>& slabs) {
  Impl& m = *impl_;
  m.first = false;
  m.step = step;
  m.time = time;
  m.current = -1;
  m.done.clear();
  if (m.index) m.index->begin_step();
  const auto t0 = std::chrono::steady_clock::now();
  if (m.isolated) m.run_isolated(slabs);
  else m.run_in_process(slabs);
  {
    std::lock_guard lock(m.mutex);
    m.timing.solver_wait_step_seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  ++m.steps_done;
  if (m.index) {
    const std::string error = m.index->write(false);
    if (!error.empty()) m.note(m.failures, error);
  }
  if (!m.load_errors.empty()) {
    std::string all;
    for (auto& e : m.load_errors) all += (all.empty() ? "" : "\n") + e;
    m.load_errors.clear();
    throw InSituLoadError(all);
  }
}

std::vector<std::string> CatalystSink::failures() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->failures;
}

std::vector<std::string> CatalystSink::incidents() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->incidents;
}

InSituTiming CatalystSink::timing() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->timing;
}

SteeringSource* CatalystSink::steering() {
  if (!impl_->has_live()) return nullptr;
  if (impl_->isolated) return &impl_->helper_steering;
  return impl_->steering.get();
}

bool CatalystSink::isolated() const { return impl_->isolated; }

vtkMultiBlockDataSet* CatalystSink::last_dataset() const { return impl_->engine ? impl_->engine->last_dataset() : nullptr; }

}  // namespace spate::catalyst
