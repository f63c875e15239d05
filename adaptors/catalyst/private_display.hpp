#pragma once
// Headless by default: when ParaView renders through X11 (Debian's build) and there is no
// DISPLAY, spate starts a private Xvfb (Mesa llvmpipe renders into it) that ends with the
// process. The display number is drawn at random from [100, 10000) and another is tried if that
// one is taken: letting Xvfb pick the first free number itself (-displayfd alone) made parallel
// runs probe :0, :1, ... together, and one such race broke another process's X connection in CI.
// The server runs with -noreset: by default an X server resets when its last client disconnects,
// and a client connecting during that reset is refused; VTK then aborts with "bad X server
// connection" (9 of 25 parallel runs did, issue 14). A ParaView built with EGL or OSMesa needs no
// display, and an existing DISPLAY is used as it is.
//
// The display belongs to the solver process, not to the in-situ helper that renders into it: when
// the helper dies, spate asks alive() to tell a lost display (restart it, retry the step, nobody to
// blame) from a pipeline that crashed.
#include <sys/types.h>

#include <string>

namespace spate::catalyst {

// In the process that renders (the in-situ helper): when the X connection breaks (the display
// went away), end the process at once with kDisplayLostExit. Xlib's default would call exit(),
// whose destructors then touch the dead connection again (a double free, and a crash handler that
// deadlocks); the solver process restarts the display and the helper instead.
inline constexpr int kDisplayLostExit = 87;
void exit_when_display_is_lost();

class PrivateDisplay {
 public:
  // Uses DISPLAY when set; else starts Xvfb if rendering needs X. Never throws: without Xvfb it
  // warns (rendering pipelines will then fail and be reported as such). With export_display the
  // process's DISPLAY is set to the private server (for rendering in this process); otherwise
  // only display() names it (for a helper's environment).
  explicit PrivateDisplay(bool export_display = true);
  ~PrivateDisplay();
  PrivateDisplay(const PrivateDisplay&) = delete;
  PrivateDisplay& operator=(const PrivateDisplay&) = delete;

  // ":N" of the display to render on (private or inherited); empty when there is none (or when
  // rendering needs no X at all).
  const std::string& display() const { return display_; }
  bool needed() const;  // whether rendering goes through X at all
  // Whether the display still accepts connections: the private server is still running, or the
  // inherited local display's socket still answers (a remote DISPLAY is assumed alive).
  bool alive() const;
  // Replaces a lost display with a fresh private Xvfb (stops the old private one). Returns false
  // if none could be started. Safe in a multithreaded process (fork + exec only).
  bool restart();

 private:
  bool start_private();
  bool export_ = true;
  pid_t server_ = -1;
  std::string display_;
};

}  // namespace spate::catalyst
