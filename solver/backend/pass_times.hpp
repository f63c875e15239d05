#pragma once
// Per-pass times of the step (issue 34): with SPATE_PASS_TIMERS=1 (or `spate bench --pass-times`)
// the slab worker brackets each pass of its step with StepKernels::begin_pass/end_pass, and `spate
// bench --json` reports the seconds each pass took on each device ("pass_seconds"). The CPU
// backend's passes are done when they return, so its clock is the host's; the CUDA backend records
// events on its stream, so a pass's time is the device's own, whatever the host does meanwhile
// (the host-time device_busy_seconds, which the balancer reads, only sees launches). Off by
// default: CUDA events cost a little, and resolving them waits for the device.
#include <array>
#include <chrono>
#include <cstdlib>
#include <stdexcept>
#include <string>

namespace spate {

enum class Pass : int {
  Predict,
  Rebuild,  // migration, the (cell, id) sort, the halo's rebuild
  EquationOfState,
  SummationDensity,
  WallState,
  WallTemperature,
  ColourGradient,
  DensityGradient,
  FluidRates,
  HaloRefresh,  // the wait for the neighbours' refreshed values, and the copies
  SpsStress,
  SpsAcceleration,
  SurfaceTension,
  AntuonoDiffusion,
  HeatRates,
  Shifting,
  Correct,
  TimeStep,
  Count
};
constexpr int kPassCount = static_cast<int>(Pass::Count);
constexpr std::array<const char*, kPassCount> kPassNames = {
    "predict",        "rebuild",          "equation_of_state", "summation_density", "wall_state",  "wall_temperature",
    "colour_gradient", "density_gradient", "fluid_rates",       "halo_refresh",      "sps_stress",  "sps_acceleration",
    "surface_tension", "antuono_diffusion", "heat_rates",       "shifting",          "correct",     "time_step"};
using PassSeconds = std::array<double, kPassCount>;

// SPATE_PASS_TIMERS: unset, empty or "0" is off, "1" on; anything else throws
// std::invalid_argument naming it.
inline bool pass_timers_enabled(const char* env) {
  const std::string v = env ? env : "";
  if (v.empty() || v == "0") return false;
  if (v == "1") return true;
  throw std::invalid_argument("SPATE_PASS_TIMERS='" + v + "': expected 0 or 1");
}
inline bool pass_timers_enabled() { return pass_timers_enabled(std::getenv("SPATE_PASS_TIMERS")); }

// The host's clock for the passes of a backend that finishes them before returning.
class HostPassClock {
 public:
  void begin() { start_ = std::chrono::steady_clock::now(); }
  void end(Pass p, PassSeconds& seconds) const {
    seconds[static_cast<int>(p)] += std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }

 private:
  std::chrono::steady_clock::time_point start_;
};

}  // namespace spate
