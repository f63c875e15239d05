#include "private_display.hpp"

#include <vtkRenderingOpenGLConfigure.h>

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>

namespace spate::catalyst {

namespace {

constexpr bool kRendersThroughX =
#if defined(VTK_USE_X) && !defined(VTK_OPENGL_HAS_EGL) && !defined(VTK_OPENGL_HAS_OSMESA)
    true;
#else
    false;
#endif

}  // namespace

namespace {

// Starts `Xvfb :number` and waits until it accepts connections (it writes the number to the pipe
// given by -displayfd then). Returns the server's pid, or -1 if it did not come up (the number is
// taken, or there is no Xvfb).
pid_t start_xvfb(int number) {
  int pipe_fd[2];
  if (pipe(pipe_fd) != 0) return -1;
  const pid_t pid = fork();
  if (pid < 0) {
    close(pipe_fd[0]);
    close(pipe_fd[1]);
    return -1;
  }
  if (pid == 0) {
    // The server ends with spate, however spate ends: VTK may touch X until the very exit.
    prctl(PR_SET_PDEATHSIG, SIGTERM);
    close(pipe_fd[0]);
    const int null = open("/dev/null", O_RDWR);
    if (null >= 0) {
      dup2(null, STDIN_FILENO);
      dup2(null, STDOUT_FILENO);
      dup2(null, STDERR_FILENO);
    }
    std::string display(1, ':');
    display += std::to_string(number);
    const std::string fd = std::to_string(pipe_fd[1]);
    execlp("Xvfb", "Xvfb", display.c_str(), "-displayfd", fd.c_str(), "-screen", "0", "1280x1024x24", "-nolisten", "tcp",
           static_cast<char*>(nullptr));
    _exit(127);
  }
  close(pipe_fd[1]);
  std::string written;
  pollfd p{pipe_fd[0], POLLIN, 0};
  while (poll(&p, 1, 20000) > 0) {
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

}  // namespace

PrivateDisplay::PrivateDisplay() {
  const char* current = std::getenv("DISPLAY");
  if (!kRendersThroughX || (current && *current)) return;
  std::random_device seed;
  std::mt19937 pick(seed() ^ static_cast<unsigned>(getpid()));
  std::uniform_int_distribution<int> number(100, 9999);
  for (int attempt = 0; attempt < 8 && server_ < 0; ++attempt) {
    const int n = number(pick);
    server_ = start_xvfb(n);
    if (server_ >= 0) display_.assign(1, ':').append(std::to_string(n));
  }
  if (server_ < 0) {
    std::fprintf(stderr,
                 "spate: warning: no DISPLAY and no Xvfb could be started; rendering pipelines will fail "
                 "(install xvfb, or run under xvfb-run; see docs/insitu.md)\n");
    return;
  }
  setenv("DISPLAY", display_.c_str(), 1);
}

// Nothing to do: VTK may hold X resources until the process exits, and the server ends then
// (PR_SET_PDEATHSIG).
PrivateDisplay::~PrivateDisplay() = default;

}  // namespace spate::catalyst
