#pragma once
// The solver's handle on its in-situ helper process (insitu_helper.hpp): starts it, talks to it,
// and says how it ended when it did. Started with posix_spawn (safe while the solver's threads run)
// in its own process group, so that a Ctrl-C in the terminal reaches only the solver, which stops
// the helper itself; killing it kills that group (anything a pipeline started goes too).
#include <sys/types.h>

#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "insitu_wire.hpp"
#include "particles/particle_memory.hpp"

namespace spate::catalyst {

class HelperProcess {
 public:
  // Spawns `program __insitu-helper` with DISPLAY set to `display` (unless empty) and the particle
  // arena handed over. Throws std::runtime_error when it cannot be started.
  HelperProcess(const std::filesystem::path& program, const std::string& display, const SharedParticleMemory& arena);
  ~HelperProcess();  // kills it if it still runs
  HelperProcess(const HelperProcess&) = delete;
  HelperProcess& operator=(const HelperProcess&) = delete;

  bool send(const nlohmann::json& message) { return wire::send(socket_, message); }
  wire::Received receive(nlohmann::json& message, double timeout_seconds) { return wire::receive(socket_, message, timeout_seconds); }

  // After the connection closed: waits (at most `seconds`, then kills) and says how it ended,
  // e.g. "killed by signal 11 (Segmentation fault)" or "exited with status 7".
  std::string reap(double seconds);
  // Kills it now (a hang) and says so.
  std::string kill_now();
  // Asks it to finalise and exit; waits at most `seconds`, then kills it. Says how it ended.
  std::string finish(double seconds);
  pid_t pid() const { return pid_; }
  // Its exit status once it has ended normally (-1 while it runs, or when a signal ended it).
  int exit_status() const { return exit_status_; }

 private:
  std::string wait_for(double seconds);
  std::string ended(int status);
  pid_t pid_ = -1;
  int socket_ = -1;
  int exit_status_ = -1;
};

}  // namespace spate::catalyst
