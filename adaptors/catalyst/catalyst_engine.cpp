#include "catalyst_engine.hpp"

#include <vtkCPDataDescription.h>
#include <vtkCPInputDataDescription.h>
#include <vtkCPPipeline.h>
#include <vtkCPProcessor.h>
#include <vtkCPPythonScriptV2Pipeline.h>
#include <vtkDataObject.h>
#include <vtkLogger.h>
#include <vtkMultiBlockDataSet.h>
#include <vtkObjectFactory.h>
#include <vtkOutputWindow.h>
#include <vtkPythonInterpreter.h>
#include <vtkSmartPointer.h>

#ifdef SPATE_CATALYST_MPI
#include <mpi.h>
#include <vtkMPI.h>
#endif

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <chrono>

#include "particle_dataset.hpp"

namespace spate::catalyst {

namespace {

using Clock = std::chrono::steady_clock;
constexpr const char* kChannel = "particles";

double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// ParaView calls a v2 script through these functions of paraview.catalyst.v2_internals (looked up
// by name on every call). Wrapped, a script's sys.exit() (or a stray KeyboardInterrupt) becomes an
// ordinary Python error of that script: Python would otherwise end the whole process, and with it
// the simulation (issue 14: sys.exit(7) ended spate with exit 7 and no outputs).
constexpr const char* kGuardScripts = R"(
import functools
from paraview.catalyst import v2_internals as _spate_v2

def _spate_guard(call):
    @functools.wraps(call)
    def guarded(*args, **kwargs):
        try:
            return call(*args, **kwargs)
        except SystemExit as e:
            raise RuntimeError("the script called sys.exit(%r); a pipeline cannot end the simulation" % (e.code,)) from e
        except KeyboardInterrupt as e:
            raise RuntimeError("KeyboardInterrupt in the script") from e
    return guarded

for _name in ("import_and_validate", "do_request_data_description", "do_catalyst_initialize",
              "do_catalyst_execute", "do_catalyst_finalize"):
    setattr(_spate_v2, _name, _spate_guard(getattr(_spate_v2, _name)))
)";

// What VTK and Python report goes to spate's log (plain text, timestamped in files, at the
// message's level), and a copy is kept while armed: that is how a pipeline's Python traceback
// reaches the failure reports and summary.json. Messages of VTK's error/warning macros reach the
// log through vtkLogger instead (see forward_vtk_log); the base class would not print those either.
class CapturingOutputWindow : public vtkOutputWindow {
 public:
  static CapturingOutputWindow* New();
  vtkTypeMacro(CapturingOutputWindow, vtkOutputWindow)
  void DisplayText(const char* text) override {
    if (!text) return;
    if (armed_) captured_ += text;
    const MessageTypes type = GetCurrentMessageType();
    if (GetDisplayStream(type) == StreamType::Null) return;
    switch (type) {
      case MESSAGE_TYPE_ERROR: spdlog::error("{}", text); break;
      case MESSAGE_TYPE_WARNING:
      case MESSAGE_TYPE_GENERIC_WARNING: spdlog::warn("{}", text); break;
      case MESSAGE_TYPE_DEBUG: spdlog::debug("{}", text); break;
      default: spdlog::info("{}", text); break;
    }
  }
  void arm() {
    captured_.clear();
    armed_ = true;
  }
  std::string disarm() {
    armed_ = false;
    return std::move(captured_);
  }

 private:
  bool armed_ = false;
  std::string captured_;
};
vtkStandardNewMacro(CapturingOutputWindow);

// vtkCPProcessor asks every pipeline twice a step: once whether anyone wants the data
// (kAsking), then once more right before each pipeline's CoProcess (kRunning).
enum class Phase { kAsking, kRunning };

// One script, guarded: sits out steps it is told to skip, tells the observer whenever it starts
// working (asking for data, or running) and when it is done for the step, remembers whether it
// failed and with what text, and its time.
class GuardedPipeline : public vtkCPPipeline {
 public:
  static GuardedPipeline* New();
  vtkTypeMacro(GuardedPipeline, vtkCPPipeline)

  void setup(int id, const std::filesystem::path& script, CapturingOutputWindow* log) {
    id_ = id;
    script_ = script;
    log_ = log;
    inner_ = vtkSmartPointer<vtkCPPythonScriptV2Pipeline>::New();
    if (!inner_->Initialize(script.c_str())) fail("ParaView could not prepare the script");
  }
  // Per step, set by the engine before the processor's calls.
  void prepare(bool skip, Phase* phase, ScriptObserver* observer) {
    skip_ = skip;
    phase_ = phase;
    observer_ = observer;
    done_ = skip;
  }

  int RequestDataDescription(vtkCPDataDescription* d) override {
    if (failed_ || skip_) return 0;
    std::string text;
    const int wants = call([&] { return inner_->RequestDataDescription(d); }, text);
    // A Python error here (the import, or the script's own RequestDataDescription) reads as "no".
    if (!wants && text.find("Traceback") != std::string::npos) fail(std::move(text));
    if (!wants && *phase_ == Phase::kRunning) finish();
    return wants;
  }
  int CoProcess(vtkCPDataDescription* d) override {
    if (failed_ || skip_) return 1;
    std::string text;
    if (!call([&] { return inner_->CoProcess(d); }, text))
      fail(text.empty() ? "the script failed (no Python error text was reported)" : text);
    finish();
    return 1;  // failures are handled by the engine, per script
  }
  int Finalize() override { return failed_ ? 1 : inner_->Finalize(); }

  // One call into the script: announced, timed, and with ParaView's and Python's output kept.
  template <class Call>
  int call(Call&& into_script, std::string& text) {
    if (observer_) observer_->started(id_);
    log_->arm();
    const auto t0 = Clock::now();
    const int result = into_script();
    seconds_ += since(t0);
    text = log_->disarm();
    return result;
  }

  // Called by the engine when the processor did not call this script again this step.
  void finish() {
    if (done_) return;
    done_ = true;
    if (observer_) observer_->finished(id_);
  }

  int id() const { return id_; }
  const std::filesystem::path& script() const { return script_; }
  bool failed() const { return failed_; }
  const std::string& error() const { return error_; }
  double seconds() const { return seconds_; }

 private:
  void fail(std::string text) {
    failed_ = true;
    error_ = std::move(text);
  }
  int id_ = 0;
  std::filesystem::path script_;
  CapturingOutputWindow* log_ = nullptr;
  vtkSmartPointer<vtkCPPythonScriptV2Pipeline> inner_;
  bool failed_ = false, skip_ = false, done_ = false;
  Phase* phase_ = nullptr;
  ScriptObserver* observer_ = nullptr;
  std::string error_;
  double seconds_ = 0.0;
};
vtkStandardNewMacro(GuardedPipeline);

// vtkLogger (loguru) writes VTK's and ParaView's messages to stderr itself, coloured whenever TERM
// names a colour terminal, even into a file. Its stderr output is switched off and its messages
// (warnings and errors; info at debug level) go to spate's log, one line each, naming the source
// file as loguru did.
void forward_vtk_log() {
  vtkLogger::SetStderrVerbosity(vtkLogger::VERBOSITY_OFF);
  vtkLogger::AddCallback(
      "spate",
      [](void*, const vtkLogger::Message& m) {
        std::string text = m.message ? m.message : "";
        while (!text.empty() && text.back() == '\n') text.pop_back();
        const std::string where = m.filename ? fmt::format(" ({}:{})", std::filesystem::path(m.filename).filename().string(), m.line) : "";
        if (m.verbosity <= vtkLogger::VERBOSITY_ERROR) spdlog::error("{}{}", text, where);
        else if (m.verbosity == vtkLogger::VERBOSITY_WARNING) spdlog::warn("{}{}", text, where);
        else spdlog::debug("{}{}", text, where);
      },
      nullptr, vtkLogger::VERBOSITY_INFO);
}

}  // namespace

struct CatalystEngine::Impl {
  EngineOptions options;
  vtkSmartPointer<vtkCPProcessor> processor;
  vtkSmartPointer<CapturingOutputWindow> log;
  std::vector<vtkSmartPointer<GuardedPipeline>> pipelines;
  std::unique_ptr<ParticleDataset> dataset;
  Phase phase = Phase::kAsking;

  void start() {
    forward_vtk_log();
    processor = vtkSmartPointer<vtkCPProcessor>::New();
    const std::string dir = options.working_dir.string();
    const char* working = dir.empty() ? nullptr : dir.c_str();
    // The run's output folder, for pipelines that read what the run wrote there (the shaped solids'
    // surfaces, geometry/solid_<material>.vtp).
    if (working) setenv("SPATE_RUN_DIR", working, 1);
    int ok = 0;
#ifdef SPATE_CATALYST_MPI
    if (options.mpi) {
      static MPI_Comm world = MPI_COMM_WORLD;
      vtkMPICommunicatorOpaqueComm comm(&world);
      ok = processor->Initialize(comm, working);
    } else {
      ok = processor->Initialize(working);
    }
#else
    ok = processor->Initialize(working);
#endif
    if (!ok) throw InSituLoadError("ParaView Catalyst failed to initialise");
    vtkPythonInterpreter::Initialize();
    if (vtkPythonInterpreter::RunSimpleString(kGuardScripts) != 0)
      throw InSituLoadError("ParaView Catalyst's Python part could not be loaded (paraview.catalyst.v2_internals)");
    log = vtkSmartPointer<CapturingOutputWindow>::New();
    vtkOutputWindow::SetInstance(log);
    dataset = std::make_unique<ParticleDataset>();
    for (auto& [name, value] : options.constants) dataset->set_constant(name, value);
    for (std::size_t k = 0; k < options.scripts.size(); ++k) {
      auto p = vtkSmartPointer<GuardedPipeline>::New();
      p->setup(k < options.ids.size() ? options.ids[k] : static_cast<int>(k), options.scripts[k], log);
      if (p->failed()) throw InSituLoadError(fmt::format("--pipeline {}: {}", options.scripts[k].string(), p->error()));
      processor->AddPipeline(p);
      pipelines.push_back(p);
    }
  }

  void stop() {
    if (processor) processor->Finalize();
    processor = nullptr;
    pipelines.clear();
    dataset.reset();
    vtkOutputWindow::SetInstance(nullptr);
    log = nullptr;
    vtkLogger::RemoveCallback("spate");
  }
};

CatalystEngine::CatalystEngine(EngineOptions options) : impl_(std::make_unique<Impl>()) {
  impl_->options = std::move(options);
  try {
    impl_->start();
  } catch (...) {
    impl_->stop();
    throw;
  }
}

CatalystEngine::~CatalystEngine() { impl_->stop(); }

bool CatalystEngine::empty() const { return impl_->pipelines.empty(); }

vtkMultiBlockDataSet* CatalystEngine::last_dataset() const { return impl_->dataset ? impl_->dataset->data() : nullptr; }

EngineStep CatalystEngine::run_step(std::int64_t step, double time, const std::vector<SlabView>& slabs, const std::set<int>& skip,
                                    ScriptObserver* observer) {
  Impl& m = *impl_;
  EngineStep result;
  std::vector<double> before;
  for (auto& p : m.pipelines) {
    p->prepare(skip.count(p->id()) > 0, &m.phase, observer);
    before.push_back(p->seconds());
  }
  vtkNew<vtkCPDataDescription> description;
  description->AddInput(kChannel);
  description->SetTimeData(time, step);
  m.phase = Phase::kAsking;
  if (m.processor->RequestDataDescription(description)) {
    vtkCPInputDataDescription* input = description->GetInputDescriptionByName(kChannel);
    // A v2 script's first request comes before it is imported and names no fields: give it all.
    std::function<bool(std::string_view)> wanted;
    if (input->GetGenerateMesh() && !input->GetAllFields())
      wanted = [input](std::string_view name) { return input->IsFieldNeeded(std::string(name).c_str(), vtkDataObject::POINT); };
    const auto t0 = Clock::now();
    input->SetGrid(m.dataset->update(slabs, wanted));
    result.adaptor_seconds = since(t0);
    result.ran = true;
    m.phase = Phase::kRunning;
    m.processor->CoProcess(description);
  }
  for (std::size_t k = 0; k < m.pipelines.size(); ++k) {
    GuardedPipeline* p = m.pipelines[k];
    p->finish();
    result.script_seconds.emplace_back(p->id(), p->seconds() - before[k]);
    if (p->failed()) result.failures.push_back({p->id(), p->error()});
  }
  // Failed scripts leave the processor (they already answer no to every request).
  for (auto it = m.pipelines.begin(); it != m.pipelines.end();) {
    if ((*it)->failed()) {
      m.processor->RemovePipeline(*it);
      it = m.pipelines.erase(it);
    } else {
      ++it;
    }
  }
  return result;
}

}  // namespace spate::catalyst
