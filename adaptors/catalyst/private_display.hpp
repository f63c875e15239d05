#pragma once
// Headless by default: when ParaView renders through X11 (Debian's build) and there is no
// DISPLAY, the adaptor starts a private Xvfb (Mesa llvmpipe renders into it) that ends with the
// process. The display number is drawn at random from [100, 10000) and another is tried if that
// one is taken: letting Xvfb pick the first free number itself (-displayfd alone) made parallel
// runs probe :0, :1, ... together, and one such race broke another process's X connection in CI.
// A ParaView built with EGL or OSMesa needs no display, and an existing DISPLAY is used as it is.
#include <sys/types.h>

#include <string>

namespace spate::catalyst {

class PrivateDisplay {
 public:
  // Starts Xvfb if rendering needs X and DISPLAY is unset; otherwise does nothing. Never throws:
  // without Xvfb it warns (rendering pipelines will then fail and be reported as such).
  PrivateDisplay();
  ~PrivateDisplay();
  PrivateDisplay(const PrivateDisplay&) = delete;
  PrivateDisplay& operator=(const PrivateDisplay&) = delete;

  const std::string& display() const { return display_; }  // ":N" when started, else empty

 private:
  pid_t server_ = -1;
  std::string display_;
};

}  // namespace spate::catalyst
