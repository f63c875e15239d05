#include "catalyst_sink.hpp"

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
#include <vtkSmartPointer.h>

#ifdef SPATE_CATALYST_MPI
#include <mpi.h>
#include <vtkMPI.h>
#endif

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdio>
#include <functional>
#include <mutex>

#include "particle_dataset.hpp"
#include "private_display.hpp"

namespace spate::catalyst {

namespace {

using Clock = std::chrono::steady_clock;
constexpr const char* kChannel = "particles";

double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// What VTK and Python report goes to spate's log (plain text, timestamped in files, at the
// message's level), and a copy is kept while armed: that is how a pipeline's Python traceback
// reaches failures() and summary.json. Messages of VTK's error/warning macros reach the log through
// vtkLogger instead (see forward_vtk_log); the base class would not print those either.
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

// One script, guarded: remembers whether it failed, on which call, with what text, and its time.
class GuardedPipeline : public vtkCPPipeline {
 public:
  static GuardedPipeline* New();
  vtkTypeMacro(GuardedPipeline, vtkCPPipeline)

  void setup(const std::filesystem::path& script, CapturingOutputWindow* log) {
    script_ = script;
    log_ = log;
    inner_ = vtkSmartPointer<vtkCPPythonScriptV2Pipeline>::New();
    if (!inner_->Initialize(script.c_str())) fail("ParaView could not prepare the script");
  }
  int RequestDataDescription(vtkCPDataDescription* d) override { return failed_ ? 0 : inner_->RequestDataDescription(d); }
  int CoProcess(vtkCPDataDescription* d) override {
    if (failed_) return 1;
    log_->arm();
    const auto t0 = Clock::now();
    const int ok = inner_->CoProcess(d);
    seconds_ += since(t0);
    std::string text = log_->disarm();
    ++calls_;
    if (!ok) fail(text.empty() ? "the script failed (no Python error text was reported)" : text);
    return 1;  // failures are handled by the sink, per script
  }
  int Finalize() override { return failed_ ? 1 : inner_->Finalize(); }

  const std::filesystem::path& script() const { return script_; }
  bool failed() const { return failed_; }
  bool failed_on_first_run() const { return failed_ && failed_at_call_ <= 1; }
  const std::string& error() const { return error_; }
  double seconds() const { return seconds_; }
  std::int64_t failed_at_step = -1;

 private:
  void fail(std::string text) {
    failed_ = true;
    failed_at_call_ = calls_;
    error_ = std::move(text);
  }
  std::filesystem::path script_;
  CapturingOutputWindow* log_ = nullptr;
  vtkSmartPointer<vtkCPPythonScriptV2Pipeline> inner_;
  bool failed_ = false;
  std::int64_t calls_ = 0, failed_at_call_ = 0;
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

struct CatalystSink::Impl {
  CatalystOptions options;
  std::unique_ptr<PrivateDisplay> display;  // outlives every VTK object below (declared first)
  vtkSmartPointer<vtkCPProcessor> processor;
  vtkSmartPointer<CapturingOutputWindow> log;
  std::vector<vtkSmartPointer<GuardedPipeline>> pipelines;
  std::unique_ptr<ParticleDataset> dataset;
  std::vector<std::string> failures;
  InSituTiming timing;
  bool first = true;
  std::atomic<int> every{1};  // options.every, then as steered (set by every slab thread)
  mutable std::mutex mutex;  // guards failures and timing, read from other threads

  void start() {
    forward_vtk_log();
    display = std::make_unique<PrivateDisplay>();
    processor = vtkSmartPointer<vtkCPProcessor>::New();
    const std::string dir = options.working_dir.string();
    const char* working = dir.empty() ? nullptr : dir.c_str();
    int ok = 0;
#ifdef SPATE_CATALYST_MPI
    int mpi = 0;
    MPI_Initialized(&mpi);
    if (mpi) {
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
    log = vtkSmartPointer<CapturingOutputWindow>::New();
    vtkOutputWindow::SetInstance(log);
    dataset = std::make_unique<ParticleDataset>();
    for (auto& [name, value] : options.constants) dataset->set_constant(name, value);
    for (auto& script : options.scripts) {
      auto p = vtkSmartPointer<GuardedPipeline>::New();
      p->setup(script, log);
      if (p->failed()) throw InSituLoadError(fmt::format("--pipeline {}: {}", script.string(), p->error()));
      processor->AddPipeline(p);
      pipelines.push_back(p);
    }
    timing.script_seconds.assign(options.scripts.size(), 0.0);
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

  void run_step(std::int64_t step, double time, const std::vector<SlabView>& slabs) {
    vtkNew<vtkCPDataDescription> description;
    description->AddInput(kChannel);
    description->SetTimeData(time, step);
    if (!processor->RequestDataDescription(description)) return;
    vtkCPInputDataDescription* input = description->GetInputDescriptionByName(kChannel);
    // A v2 script's first request comes before it is imported and names no fields: give it all.
    std::function<bool(std::string_view)> wanted;
    if (input->GetGenerateMesh() && !input->GetAllFields())
      wanted = [input](std::string_view name) { return input->IsFieldNeeded(std::string(name).c_str(), vtkDataObject::POINT); };

    const auto t0 = Clock::now();
    input->SetGrid(dataset->update(slabs, wanted));
    const double adaptor = since(t0);

    std::vector<double> before;
    for (auto& p : pipelines) before.push_back(p->seconds());
    processor->CoProcess(description);

    std::vector<std::string> load_errors;
    std::lock_guard lock(mutex);
    timing.steps += 1;
    timing.adaptor_seconds += adaptor;
    timing.adaptor_step_seconds.push_back(adaptor);
    timing.pipelines_step_seconds.push_back(0.0);
    for (std::size_t k = 0; k < pipelines.size(); ++k) {
      GuardedPipeline* p = pipelines[k];
      const double spent = p->seconds() - before[k];
      timing.pipelines_seconds += spent;
      timing.pipelines_step_seconds.back() += spent;
      for (std::size_t s = 0; s < options.scripts.size(); ++s)
        if (options.scripts[s] == p->script()) timing.script_seconds[s] += spent;
      if (!p->failed() || p->failed_at_step >= 0) continue;
      p->failed_at_step = step;
      if (p->failed_on_first_run()) {
        load_errors.push_back(fmt::format("--pipeline {}: the script failed to load:\n{}", p->script().string(), p->error()));
      } else {
        spdlog::warn("in-situ pipeline {} failed at step {} and is switched off; the run continues", p->script().string(), step);
        failures.push_back(fmt::format("{}: failed at step {} (t = {:.6g} s), switched off:\n{}", p->script().string(), step, time, p->error()));
      }
    }
    // Switched-off scripts leave the processor (they already answer no to every request).
    for (auto it = pipelines.begin(); it != pipelines.end();) {
      if ((*it)->failed()) {
        processor->RemovePipeline(*it);
        it = pipelines.erase(it);
      } else {
        ++it;
      }
    }
    if (!load_errors.empty()) {
      std::string all;
      for (auto& e : load_errors) all += (all.empty() ? "" : "\n") + e;
      throw InSituLoadError(all);
    }
  }
};

CatalystSink::CatalystSink(CatalystOptions options) : impl_(std::make_unique<Impl>()) {
  if (options.every < 1) throw InSituLoadError(fmt::format("--insitu-every {}: must be at least 1", options.every));
  for (auto& script : options.scripts) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(script, ec) && !std::filesystem::is_directory(script, ec))
      throw InSituLoadError(fmt::format("--pipeline {}: no such script", script.string()));
    script = std::filesystem::absolute(script);
  }
  if (!options.working_dir.empty()) options.working_dir = std::filesystem::absolute(options.working_dir);
  impl_->every = options.every;
  impl_->options = std::move(options);
  try {
    impl_->start();
  } catch (...) {
    impl_->stop();
    throw;
  }
}

CatalystSink::~CatalystSink() {
  try {
    impl_->stop();
  } catch (const std::exception& e) {
    spdlog::error("finalising Catalyst: {}", e.what());
  }
}

bool CatalystSink::wants(std::int64_t step, double) {
  if (impl_->pipelines.empty()) return false;
  return impl_->first || step % impl_->every.load() == 0;
}

void CatalystSink::set_interval(int every) {
  if (every >= 1) impl_->every.store(every);
}

void CatalystSink::execute(std::int64_t step, double time, const std::vector<SlabView>& slabs) {
  impl_->first = false;
  impl_->run_step(step, time, slabs);
}

std::vector<std::string> CatalystSink::failures() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->failures;
}

InSituTiming CatalystSink::timing() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->timing;
}

vtkMultiBlockDataSet* CatalystSink::last_dataset() const { return impl_->dataset ? impl_->dataset->data() : nullptr; }

}  // namespace spate::catalyst
