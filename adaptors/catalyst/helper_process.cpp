#include "helper_process.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fmt/format.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <stdexcept>
#include <thread>
#include <vector>

#include "insitu_helper.hpp"

extern char** environ;

namespace spate::catalyst {

namespace {

std::string describe(int status) {
  if (WIFSIGNALED(status)) {
    const int s = WTERMSIG(status);
    return fmt::format("killed by signal {} ({})", s, strsignal(s));
  }
  if (WIFEXITED(status)) return fmt::format("exited with status {}", WEXITSTATUS(status));
  return "ended";
}

}  // namespace

HelperProcess::HelperProcess(const std::filesystem::path& program, const std::string& display, const SharedParticleMemory& arena) {
  int pair[2];
  if (socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0, pair) != 0)
    throw std::runtime_error(fmt::format("in-situ helper: socketpair: {}", std::strerror(errno)));
  // The child gets its end as fd 3 and the arena as fd 4 (dup2 clears close-on-exec there). Both
  // are first copied above 10, so that neither source is 3 or 4 itself.
  const int child_end = fcntl(pair[1], F_DUPFD_CLOEXEC, 10), arena_fd = fcntl(arena.fd, F_DUPFD_CLOEXEC, 10);
  close(pair[1]);
  posix_spawn_file_actions_t files;
  posix_spawn_file_actions_init(&files);
  posix_spawn_file_actions_adddup2(&files, child_end, 3);
  posix_spawn_file_actions_adddup2(&files, arena_fd, 4);
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  posix_spawnattr_setpgroup(&attr, 0);
  sigset_t none;
  sigemptyset(&none);
  posix_spawnattr_setsigmask(&attr, &none);
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETPGROUP | POSIX_SPAWN_SETSIGMASK);

  const std::string parent = std::to_string(getpid());
  const std::string exe = program.string();
  const char* argv[] = {"spate", kHelperCommand, "3", "4", parent.c_str(), nullptr};
  std::vector<std::string> env_text;
  for (char** e = environ; e && *e; ++e)
    if (std::strncmp(*e, "DISPLAY=", 8) != 0) env_text.emplace_back(*e);
  if (!display.empty()) env_text.push_back("DISPLAY=" + display);
  std::vector<char*> env;
  for (auto& e : env_text) env.push_back(e.data());
  env.push_back(nullptr);

  const int rc = posix_spawn(&pid_, exe.c_str(), &files, &attr, const_cast<char* const*>(argv), env.data());
  posix_spawn_file_actions_destroy(&files);
  posix_spawnattr_destroy(&attr);
  close(child_end);
  close(arena_fd);
  if (rc != 0) {
    close(pair[0]);
    throw std::runtime_error(fmt::format("in-situ helper: cannot start {}: {}", exe, std::strerror(rc)));
  }
  socket_ = pair[0];
}

HelperProcess::~HelperProcess() {
  if (pid_ > 0) {
    kill(-pid_, SIGKILL);
    waitpid(pid_, nullptr, 0);
  }
  if (socket_ >= 0) close(socket_);
}

std::string HelperProcess::wait_for(double seconds) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  int status = 0;
  for (;;) {
    const pid_t r = waitpid(pid_, &status, WNOHANG);
    if (r == pid_) break;
    if (r < 0 && errno != EINTR) return "ended";
    if (std::chrono::steady_clock::now() > deadline) {
      kill(-pid_, SIGKILL);
      waitpid(pid_, &status, 0);
      pid_ = -1;
      return fmt::format("did not end within {:g} s and was killed", seconds);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return ended(status);
}

std::string HelperProcess::ended(int status) {
  pid_ = -1;
  if (WIFEXITED(status)) exit_status_ = WEXITSTATUS(status);
  return describe(status);
}

std::string HelperProcess::reap(double seconds) { return pid_ > 0 ? wait_for(seconds) : "ended"; }

std::string HelperProcess::kill_now() {
  if (pid_ <= 0) return "ended";
  kill(-pid_, SIGKILL);
  int status = 0;
  waitpid(pid_, &status, 0);
  return ended(status);
}

std::string HelperProcess::finish(double seconds) {
  if (pid_ <= 0) return "ended";
  if (send({{"type", "finish"}})) {
    nlohmann::json reply;
    const auto t0 = std::chrono::steady_clock::now();
    while (receive(reply, seconds) == wire::Received::kMessage && reply.value("type", "") != "finished_all")
      if (std::chrono::steady_clock::now() - t0 > std::chrono::duration<double>(seconds)) break;
  }
  return wait_for(seconds);
}

}  // namespace spate::catalyst
