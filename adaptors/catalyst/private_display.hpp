#pragma once
// Headless by default: when ParaView renders through X11 (Debian's build) and there is no
// DISPLAY, the adaptor starts a private Xvfb (Mesa llvmpipe renders into it) that ends with the
// process. Xvfb picks a free display itself (-displayfd), so parallel runs on one
// machine never race for a number. A ParaView built with EGL or OSMesa needs no display, and an
// existing DISPLAY is used as it is.
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
