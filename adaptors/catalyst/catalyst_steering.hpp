#pragma once
// Steering from ParaView Catalyst Live: the steering parameters are the properties of one proxy
// (pipelines/spate_steering.xml, registered as 'steering' in the 'sources' group of the in-situ
// proxy manager). A Live client edits the proxy; the edit reaches the simulation during the next
// live step (inside CoProcess, on every rank). poll() reports the properties that changed since the
// last poll as SteeringChange entries; the solver validates and applies them (solver/sim/steering).
//
// Construct after the CatalystEngine (which starts ParaView's proxy manager), in the process that
// runs Catalyst (the in-situ helper, or the solver under MPI), and use on the main thread. The simulation never listens: the Live connection is made by ParaView's script pipeline
// (pipelines/live.py), which connects out to the configured host.
#include <array>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "catalyst_engine.hpp"
#include "sim/steering.hpp"

namespace spate::catalyst {

// The values the proxy starts with: the run's current parameters, so that a client sees them.
struct SteeringInitial {
  std::array<double, 3> gravity{0.0, -9.81, 0.0};
  double viscosity = 0.0;
  std::array<double, 2> phase_viscosity{0.0, 0.0};   // fluid number, its dynamic viscosity [Pa s]
  double artificial_viscosity = 0.0;
  std::array<double, 2> motion_amplitude{0.0, 1.0};  // motion number, amplitude scale
  std::array<double, 2> motion_frequency{0.0, 0.0};  // motion number, frequency [Hz]
  std::array<double, 2> face_temperature{0.0, 293.15};  // tank face number, its temperature [K]
  std::array<double, 2> face_heat_flux{0.0, 0.0};        // tank face number, heat flux into the fluid [W/m2]
  std::array<double, 2> spring_stiffness{0.0, 0.0};  // spring number, its stiffness [N/m]
  std::array<double, 2> spring_damping{0.0, 0.0};    // spring number, its damping [N s/m]
  std::array<double, 2> hinge_stiffness{0.0, 0.0};   // floating solid number, its hinge's stiffness [N m/rad]
  std::array<double, 2> hinge_damping{0.0, 0.0};     // floating solid number, its hinge's damping [N m s/rad]
  int insitu_every = 1;

  // Shows an accepted change (a restart's history, or one steered before a fresh in-situ helper
  // started), so that a client sees the run's current values.
  void take(const SteeringChange& change);
};

class CatalystSteering final : public SteeringSource {
 public:
  static constexpr const char* kRegistrationName = "steering";
  static constexpr const char* kProxyType = "SpateSteeringParameters";

  // Loads the proxy definition (the XML) into ParaView and creates the proxy with `initial`.
  // Throws InSituLoadError when the XML cannot be loaded or the proxy cannot be created.
  CatalystSteering(const std::filesystem::path& xml, const SteeringInitial& initial);
  ~CatalystSteering() override;

  std::vector<SteeringChange> poll(std::int64_t step, double time) override;

  // The proxy's current values, by parameter name (for tests and messages).
  std::map<std::string, std::vector<double>> values() const;
  // For tests: set a property as a Live client's edit would (then UpdateVTKObjects).
  void set_for_test(const std::string& name, const std::vector<double>& value);

 private:
  std::map<std::string, std::vector<double>> last_;  // as seen at the previous poll
};

}  // namespace spate::catalyst
