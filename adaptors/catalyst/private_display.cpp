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

namespace spate::catalyst {

namespace {

constexpr bool kRendersThroughX =
#if defined(VTK_USE_X) && !defined(VTK_OPENGL_HAS_EGL) && !defined(VTK_OPENGL_HAS_OSMESA)
    true;
#else
    false;
#endif

}  // namespace

PrivateDisplay::PrivateDisplay() {
  const char* current = std::getenv("DISPLAY");
  if (!kRendersThroughX || (current && *current)) return;
  int pipe_fd[2];
  if (pipe(pipe_fd) != 0) return;
  const pid_t pid = fork();
  if (pid < 0) {
    close(pipe_fd[0]);
    close(pipe_fd[1]);
    return;
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
    const std::string fd = std::to_string(pipe_fd[1]);
    execlp("Xvfb", "Xvfb", "-displayfd", fd.c_str(), "-screen", "0", "1280x1024x24", "-nolisten", "tcp", static_cast<char*>(nullptr));
    _exit(127);
  }
  close(pipe_fd[1]);
  // Xvfb writes its display number once it accepts connections.
  std::string number;
  pollfd p{pipe_fd[0], POLLIN, 0};
  while (poll(&p, 1, 20000) > 0) {
    char c;
    if (read(pipe_fd[0], &c, 1) != 1 || c == '\n') break;
    number += c;
  }
  close(pipe_fd[0]);
  if (number.empty()) {
    kill(pid, SIGTERM);
    waitpid(pid, nullptr, 0);
    std::fprintf(stderr,
                 "spate: warning: no DISPLAY and no Xvfb could be started; rendering pipelines will fail "
                 "(install xvfb, or run under xvfb-run; see docs/insitu.md)\n");
    return;
  }
  server_ = pid;
  display_ = ":" + number;
  setenv("DISPLAY", display_.c_str(), 1);
}

// Nothing to do: VTK may hold X resources until the process exits, and the server ends then
// (PR_SET_PDEATHSIG).
PrivateDisplay::~PrivateDisplay() = default;

}  // namespace spate::catalyst
