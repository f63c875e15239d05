#include "insitu_helper.hpp"

#include <vtkPythonInterpreter.h>

#include <dirent.h>
#include <linux/tcp.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <fmt/format.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <thread>

#include "catalyst_engine.hpp"
#include "catalyst_steering.hpp"
#include "insitu_wire.hpp"
#include "io/log.hpp"
#include "private_display.hpp"

namespace spate::catalyst {

namespace {

using Clock = std::chrono::steady_clock;
constexpr std::size_t kMaxErrorText = 64 * 1024;  // a traceback longer than this is cut (messages stay small)

std::string cut(std::string text) {
  if (text.size() > kMaxErrorText) text = text.substr(0, kMaxErrorText / 2) + "\n[...]\n" + text.substr(text.size() - kMaxErrorText / 2);
  return text;
}

// Catalyst Live connects out with a blocking connect and handshake inside ParaView; a peer that
// accepts and never answers would hold the simulation for ever. While the live script runs, this
// watch looks at the helper's own TCP connections to the live ports (PORT for commands, PORT+1
// for data) and ends the helper when one has been connecting, or connected without receiving a
// single byte, for longer than the timeout. A paused client is not affected: it has answered.
class LiveHandshakeWatch {
 public:
  LiveHandshakeWatch(int port, double timeout, int socket) : port_(port), timeout_(timeout), socket_(socket) {
    thread_ = std::thread([this] { loop(); });
  }
  ~LiveHandshakeWatch() {
    stop_ = true;
    thread_.join();
  }
  void arm(bool on) { armed_ = on; }

 private:
  // inode -> fd of this process's sockets.
  static std::map<unsigned long, int> sockets() {
    std::map<unsigned long, int> out;
    DIR* d = opendir("/proc/self/fd");
    if (!d) return out;
    while (dirent* e = readdir(d)) {
      const int fd = std::atoi(e->d_name);
      struct stat st {};
      if (fd > 2 && fstat(fd, &st) == 0 && S_ISSOCK(st.st_mode)) out[st.st_ino] = fd;
    }
    closedir(d);
    return out;
  }

  // Connections to the live ports that are still waiting for the peer's first byte (by inode).
  std::vector<unsigned long> waiting() const {
    std::vector<unsigned long> out;
    const auto mine = sockets();
    for (const char* table : {"/proc/self/net/tcp", "/proc/self/net/tcp6"}) {
      std::ifstream in(table);
      std::string line;
      std::getline(in, line);
      while (std::getline(in, line)) {
        std::istringstream row(line);
        std::string slot, local, remote, state, queues, timer, retransmits, uid, timeout_field;
        unsigned long inode = 0;
        row >> slot >> local >> remote >> state >> queues >> timer >> retransmits >> uid >> timeout_field >> inode;
        const auto colon = remote.rfind(':');
        if (colon == std::string::npos || !mine.count(inode)) continue;
        const int port = static_cast<int>(std::strtol(remote.c_str() + colon + 1, nullptr, 16));
        if (port != port_ && port != port_ + 1) continue;
        if (state == "02") {  // SYN_SENT
          out.push_back(inode);
        } else if (state == "01") {  // ESTABLISHED: has the peer said anything yet?
          tcp_info info{};
          socklen_t len = sizeof info;
          if (getsockopt(mine.at(inode), IPPROTO_TCP, TCP_INFO, &info, &len) == 0 &&
              len >= offsetof(tcp_info, tcpi_bytes_received) + sizeof info.tcpi_bytes_received && info.tcpi_bytes_received == 0)
            out.push_back(inode);
        }
      }
    }
    return out;
  }

  void loop() {
    std::map<unsigned long, Clock::time_point> since;
    while (!stop_) {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
      if (!armed_) {
        since.clear();
        continue;
      }
      const auto now = Clock::now();
      std::map<unsigned long, Clock::time_point> still;
      for (unsigned long inode : waiting()) {
        const auto it = since.find(inode);
        const auto t0 = it == since.end() ? now : it->second;
        still[inode] = t0;
        if (std::chrono::duration<double>(now - t0).count() > timeout_) {
          wire::send(socket_, {{"type", "live_timeout"},
                               {"message", fmt::format("the peer at port {} did not complete ParaView's Catalyst Live handshake "
                                                       "within {:g} s (insitu.live_timeout)", port_, timeout_)}});
          std::fflush(nullptr);
          _exit(kLiveHandshakeTimeoutExit);
        }
      }
      since = std::move(still);
    }
  }

  int port_;
  double timeout_;
  int socket_;
  std::atomic<bool> armed_{false}, stop_{false};
  std::thread thread_;
};

// Tells the solver which script runs (so that it can blame a crash or hang on it), and arms the
// live watch while the live script runs.
class Reporter : public ScriptObserver {
 public:
  Reporter(int socket, int live_id, LiveHandshakeWatch* watch) : socket_(socket), live_id_(live_id), watch_(watch) {}
  // A script is announced once per stretch of work (ParaView asks it twice, then runs it).
  void started(int id) override {
    if (id == running_) return;
    running_ = id;
    wire::send(socket_, {{"type", "started"}, {"id", id}});
    if (watch_ && id == live_id_) watch_->arm(true);
  }
  void finished(int id) override {
    if (watch_ && id == live_id_) watch_->arm(false);
    running_ = -1;
    wire::send(socket_, {{"type", "finished"}, {"id", id}});
  }

 private:
  int socket_, live_id_;
  int running_ = -1;
  LiveHandshakeWatch* watch_;
};

// Maps the solver's arena read-only (pipelines must not write solver memory; one that tries
// crashes this process, not the solver), at the solver's address if that range is free here.
// Returns the shift to add to the solver's addresses, or throws.
std::intptr_t map_arena(int fd, std::uintptr_t base, std::size_t size) {
  void* at = mmap(reinterpret_cast<void*>(base), size, PROT_READ, MAP_SHARED | MAP_FIXED_NOREPLACE, fd, 0);
  if (at == MAP_FAILED) at = mmap(nullptr, size, PROT_READ, MAP_SHARED, fd, 0);
  if (at == MAP_FAILED) throw std::runtime_error("cannot map the solver's particle memory");
  return static_cast<std::intptr_t>(reinterpret_cast<std::uintptr_t>(at) - base);
}

SteeringInitial initial_from(const nlohmann::json& j) {
  SteeringInitial s;
  for (int k = 0; k < 3; ++k) s.gravity[k] = j.at("gravity").at(k).get<double>();
  s.viscosity = j.at("viscosity").get<double>();
  s.phase_viscosity = j.at("phase_viscosity").get<std::array<double, 2>>();
  s.artificial_viscosity = j.at("artificial_viscosity").get<double>();
  s.motion_amplitude = j.at("motion_amplitude").get<std::array<double, 2>>();
  s.motion_frequency = j.at("motion_frequency").get<std::array<double, 2>>();
  s.face_temperature = j.at("face_temperature").get<std::array<double, 2>>();
  s.face_heat_flux = j.at("face_heat_flux").get<std::array<double, 2>>();
  s.spring_stiffness = j.at("spring_stiffness").get<std::array<double, 2>>();
  s.spring_damping = j.at("spring_damping").get<std::array<double, 2>>();
  s.hinge_stiffness = j.at("hinge_stiffness").get<std::array<double, 2>>();
  s.hinge_damping = j.at("hinge_damping").get<std::array<double, 2>>();
  s.insitu_every = j.at("insitu_every").get<int>();
  return s;
}

int serve(int socket, int arena_fd) {
  nlohmann::json init;
  if (wire::receive(socket, init, -1) != wire::Received::kMessage || init.value("type", "") != "init") return 1;
  configure_logging(static_cast<spdlog::level::level_enum>(init.value("log_level", static_cast<int>(spdlog::level::info))));
  try {
    const auto& arena = init.at("arena");
    const std::intptr_t shift = map_arena(arena_fd, arena.at("base").get<std::uintptr_t>(), arena.at("size").get<std::size_t>());

    EngineOptions eo;
    for (const auto& s : init.at("scripts")) eo.scripts.emplace_back(s.get<std::string>());
    eo.ids = init.at("ids").get<std::vector<int>>();
    eo.working_dir = init.at("working_dir").get<std::string>();
    for (const auto& [name, value] : init.at("constants").items()) eo.constants.emplace_back(name, value.get<double>());
    auto engine = std::make_unique<CatalystEngine>(eo);
    // ParaView installs crash handlers (loguru) that print a stack trace with malloc and friends
    // from inside the signal handler; after heap corruption they deadlock, and the solver would wait
    // for its timeout. A crash here ends this process at once; the solver reports the signal.
    for (int s : {SIGSEGV, SIGABRT, SIGBUS, SIGFPE, SIGILL}) signal(s, SIG_DFL);
    exit_when_display_is_lost();
    // ParaView's Python modules load here, before any script's clock starts (they take seconds).
    vtkPythonInterpreter::RunSimpleString("import paraview.simple\nfrom paraview import catalyst\n");

    std::unique_ptr<CatalystSteering> steering;
    std::unique_ptr<LiveHandshakeWatch> watch;
    int live_id = -1;
    if (init.contains("live") && !init["live"].is_null()) {
      const auto& live = init["live"];
      live_id = live.at("id").get<int>();
      steering = std::make_unique<CatalystSteering>(live.at("xml").get<std::string>(), initial_from(live.at("initial")));
      const std::string url = live.at("url").get<std::string>();
      watch = std::make_unique<LiveHandshakeWatch>(std::atoi(url.substr(url.rfind(':') + 1).c_str()), live.at("timeout").get<double>(),
                                                   socket);
    }
    Reporter reporter(socket, live_id, watch.get());
    wire::send(socket, {{"type", "ready"}});

    for (;;) {
      nlohmann::json in;
      if (wire::receive(socket, in, -1) != wire::Received::kMessage) break;  // the solver is gone
      const std::string type = in.value("type", "");
      if (type == "finish") break;
      if (type != "step") continue;
      const auto step = in.at("step").get<std::int64_t>();
      const double time = in.at("time").get<double>();
      const auto skip = in.at("skip").get<std::set<int>>();
      const EngineStep r = engine->run_step(step, time, wire::slabs_from_json(in.at("slabs"), shift), skip, &reporter);
      nlohmann::json done = {{"type", "done"}, {"ran", r.ran}, {"adaptor_seconds", r.adaptor_seconds}};
      done["script_seconds"] = nlohmann::json::array();
      for (auto& [id, seconds] : r.script_seconds) done["script_seconds"].push_back({id, seconds});
      done["failures"] = nlohmann::json::array();
      for (auto& f : r.failures) done["failures"].push_back({{"id", f.id}, {"error", cut(f.error)}});
      done["steering"] = nlohmann::json::array();
      if (steering)
        for (auto& c : steering->poll(step, time)) done["steering"].push_back({{"name", c.name}, {"value", c.value}});
      if (!wire::send(socket, done)) break;
    }
    watch.reset();
    steering.reset();  // unregisters its proxy while ParaView is still up
    engine.reset();    // finalises Catalyst
    wire::send(socket, {{"type", "finished_all"}});
  } catch (const std::exception& e) {
    wire::send(socket, {{"type", "error"}, {"message", cut(e.what())}});
  }
  return 0;
}

}  // namespace

int run_insitu_helper(int argc, char** argv) {
  if (argc != 5) {
    std::fprintf(stderr, "spate: %s is started by spate itself (in-situ helper), not by hand\n", kHelperCommand);
    return 2;
  }
  const int socket = std::atoi(argv[2]), arena = std::atoi(argv[3]);
  const pid_t parent = static_cast<pid_t>(std::atol(argv[4]));
  // Dies with the solver, however the solver ends; terminal signals are the solver's to handle.
  prctl(PR_SET_PDEATHSIG, SIGKILL);
  if (getppid() != parent) return 1;
  signal(SIGINT, SIG_IGN);
  // When memory runs out, the kernel should end a pipeline's greed here, not the solver.
  if (std::FILE* f = std::fopen("/proc/self/oom_score_adj", "w")) {
    std::fputs("500", f);
    std::fclose(f);
  }
  configure_logging(spdlog::level::info);
  const int status = serve(socket, arena);
  // VTK's and Python's static destructors at exit can hang or crash; everything is finalised.
  std::fflush(nullptr);
  _exit(status);
}

}  // namespace spate::catalyst
