#include "private_display.hpp"

#include <vtkRenderingOpenGLConfigure.h>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#if defined(VTK_USE_X)
#include <X11/Xlib.h>
#endif

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace spate::catalyst {

namespace {

constexpr bool kRendersThroughX =
#if defined(VTK_USE_X) && !defined(VTK_OPENGL_HAS_EGL) && !defined(VTK_OPENGL_HAS_OSMESA)
    true;
#else
    false;
#endif

// Xvfb's path from PATH, found before any fork (the child may only call async-signal-safe code).
std::string find_xvfb() {
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path ? path : "/usr/bin:/bin");
  for (std::string dir; std::getline(dirs, dir, ':');) {
    const std::string candidate = (dir.empty() ? "." : dir) + "/Xvfb";
    if (access(candidate.c_str(), X_OK) == 0) return candidate;
  }
  return {};
}

// Starts `Xvfb :number` and waits until it accepts connections (it writes the number to the pipe
// given by -displayfd then). Returns the server's pid, or -1 if it did not come up (the number is
// taken, or there is no Xvfb). Everything the child needs is prepared before fork, so this is safe
// in a multithreaded process.
pid_t start_xvfb(const std::string& program, int number) {
  int pipe_fd[2];
  if (pipe2(pipe_fd, O_CLOEXEC) != 0) return -1;
  const std::string display = fmt::format(":{}", number);
  const std::string fd = std::to_string(pipe_fd[1]);
  const char* argv[] = {"Xvfb", display.c_str(), "-displayfd", fd.c_str(), "-screen", "0", "1280x1024x24",
                        "-nolisten", "tcp", "-noreset", nullptr};
  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid < 0) {
    close(pipe_fd[0]);
    close(pipe_fd[1]);
    return -1;
  }
  if (pid == 0) {
    // The server ends with spate, however spate ends: VTK may touch X until the very exit.
    prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (getppid() != parent) _exit(0);
    const int flags = fcntl(pipe_fd[1], F_GETFD);
    fcntl(pipe_fd[1], F_SETFD, flags & ~FD_CLOEXEC);  // the write end goes to Xvfb
    const int null = open("/dev/null", O_RDWR);
    if (null >= 0) {
      dup2(null, STDIN_FILENO);
      dup2(null, STDOUT_FILENO);
      dup2(null, STDERR_FILENO);
    }
    execv(program.c_str(), const_cast<char* const*>(argv));
    _exit(127);
  }
  close(pipe_fd[1]);
  std::string written;
  pollfd p{pipe_fd[0], POLLIN, 0};
  // A loaded machine (many runs starting together) can take tens of seconds to start a server.
  while (poll(&p, 1, 60000) > 0) {
    char c;
    if (read(pipe_fd[0], &c, 1) != 1 || c == '\n') break;
    written += c;
  }
  close(pipe_fd[0]);
  if (written == std::to_string(number)) return pid;
  kill(pid, SIGTERM);
  waitpid(pid, nullptr, 0);
  return -1;
}

// Whether a local X display (":N" or ":N.S") accepts a connection on its Unix socket (the
// abstract one Linux servers open, else the file one). Other forms (host:N) are assumed alive.
bool local_display_answers(const std::string& display) {
  if (display.empty() || display[0] != ':') return true;
  const std::string number = display.substr(1, display.find('.') == std::string::npos ? std::string::npos : display.find('.') - 1);
  const std::string path = "/tmp/.X11-unix/X" + number;
  for (bool abstract : {true, false}) {
    const int s = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (s < 0) return true;
    sockaddr_un a{};
    a.sun_family = AF_UNIX;
    const std::size_t offset = abstract ? 1 : 0;
    std::memcpy(a.sun_path + offset, path.c_str(), std::min(path.size(), sizeof a.sun_path - 1 - offset));
    const socklen_t len = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + offset + path.size());
    const bool ok = connect(s, reinterpret_cast<sockaddr*>(&a), len) == 0;
    close(s);
    if (ok) return true;
  }
  return false;
}

}  // namespace

void exit_when_display_is_lost() {
#if defined(VTK_USE_X)
  XSetIOErrorHandler([](Display*) -> int {
    static const char text[] = "spate: in situ: the X display was lost\n";
    [[maybe_unused]] const ssize_t n = write(STDERR_FILENO, text, sizeof text - 1);
    _exit(kDisplayLostExit);
  });
#endif
}

PrivateDisplay::PrivateDisplay(bool export_display) : export_(export_display) {
  if (!kRendersThroughX) return;
  const char* current = std::getenv("DISPLAY");
  if (current && *current) {
    display_ = current;
    return;
  }
  if (!start_private())
    spdlog::warn("no DISPLAY and no Xvfb could be started; rendering pipelines will fail (install xvfb, or run under "
                 "xvfb-run; see docs/insitu.md)");
}

bool PrivateDisplay::start_private() {
  const std::string program = find_xvfb();
  if (program.empty()) return false;
  std::random_device seed;
  std::mt19937 pick(seed() ^ static_cast<unsigned>(getpid()));
  std::uniform_int_distribution<int> number(100, 9999);
  for (int attempt = 0; attempt < 8; ++attempt) {
    const int n = number(pick);
    server_ = start_xvfb(program, n);
    if (server_ >= 0) {
      display_ = fmt::format(":{}", n);
      if (export_) setenv("DISPLAY", display_.c_str(), 1);
      return true;
    }
  }
  return false;
}

bool PrivateDisplay::needed() const { return kRendersThroughX; }

bool PrivateDisplay::alive() const {
  if (!kRendersThroughX) return true;
  if (display_.empty()) return false;
  if (server_ >= 0) {
    int status = 0;
    if (waitpid(server_, &status, WNOHANG) != 0) return false;
  }
  return local_display_answers(display_);
}

bool PrivateDisplay::restart() {
  if (!kRendersThroughX) return true;
  if (server_ >= 0) {
    kill(server_, SIGTERM);
    waitpid(server_, nullptr, 0);
    server_ = -1;
  }
  display_.clear();
  return start_private();
}

// Nothing to do: VTK may hold X resources until the process exits, and the server ends then
// (PR_SET_PDEATHSIG).
PrivateDisplay::~PrivateDisplay() = default;

}  // namespace spate::catalyst
