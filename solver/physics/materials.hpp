#pragma once
// Materials: every particle carries a one-byte material index (the registry field `material`) into
// a small table. Fluids come first, then the walls:
//   [0, fluids)        fluids, each with its own rest density, mass, viscosity, sound speed, Tait
//                      exponent and background pressure (`fluid:` or the `fluids:` list of the case)
//   fluids             the tank's walls
//   fluids + 1 + k     solid k of the case (its own material, so that force probes and motions can
//                      name it)
// Fluids first keeps "is this a fluid?" one comparison, which the vectorised pair loops need.
// With one fluid the numbering is the one checkpoints and pipelines have always used (0 fluid,
// 1 tank wall, 2 + k solid k: the exported array `kind`).
//
// Plain data, passed by value to CUDA kernels inside PhysicsParams.
#include <cstdint>

#include "host_device.hpp"

namespace spate {

constexpr int kMaxFluids = 8;
constexpr int kMaxMaterials = 256;  // the index is one byte

// A fluid's properties, as the pair terms and the equation of state read them.
struct FluidMaterial {
  float rho0 = 1000.0f;             // rest density [kg/m3]
  float mass = 1.0f;                // particle mass rho0 dp^dim [kg]
  float viscosity = 1.0e-3f;        // dynamic viscosity mu [Pa s]
  float c0 = 20.0f;                 // artificial sound speed [m/s]
  float gamma = 7.0f;               // Tait exponent (eq. 9)
  float inv_gamma = 1.0f / 7.0f;
  float tait_b = 0.0f;              // c0^2 rho0 / gamma [Pa]
  float background_pressure = 0.0f; // added to the Tait pressure (a light phase may need one) [Pa]
};

// The fluid with these properties (tait_b and 1/gamma derived, rounded as they always were).
inline FluidMaterial make_fluid(float rho0, float c0, float gamma, float viscosity, float mass, float background = 0.0f) {
  FluidMaterial m;
  m.rho0 = rho0;
  m.c0 = c0;
  m.gamma = gamma;
  m.inv_gamma = 1.0f / gamma;
  m.tait_b = c0 * c0 * rho0 / gamma;
  m.viscosity = viscosity;
  m.mass = mass;
  m.background_pressure = background;
  return m;
}

// What a shaped wall (a shaped tank, a solid) does to the fluid sliding along it, from each of its
// particles' own surface frame (wall_boundary.hpp WallFrame): Adami's no slip, free slip, or the
// log law's turbulent shear (`free_slip` and `wall_shear` of the tank or a solid). A box tank's
// faces keep theirs in PhysicsParams (free_slip_axes, wall_shear) and need no frame.
enum class FaceShear : std::uint8_t { NoSlip, FreeSlip, LogLaw };

struct MaterialTable {
  std::uint8_t fluids = 1;  // materials [0, fluids) are fluids
  std::uint8_t count = 2;   // fluids, the tank, the solids
  // The reference fluid: the stiffest (largest c0^2 rho0 / gamma), whose equation of state gives
  // every wall particle its density (Adami) and whose particles walls stand in for. With one fluid,
  // that fluid; with water and air, the water (docs/physics.md, "Several fluids").
  std::uint8_t reference = 0;
  FluidMaterial fluid[kMaxFluids];
  // Per wall material: 0 static, k + 1 moving with the case's motion k (PhysicsParams::motion).
  std::uint8_t motion[kMaxMaterials] = {};
  // Per wall material: what its surface does (FaceShear); NoSlip for all, and for every fluid,
  // unless a shaped wall slides or follows the log law.
  FaceShear face_shear[kMaxMaterials] = {};
  bool face_frames = false;  // some material's face_shear is not NoSlip (the kWallFrame fields)
  bool faces_slide = false;  // some material's face_shear is FreeSlip

  SPATE_HD bool is_fluid(std::uint8_t m) const { return m < fluids; }
  SPATE_HD std::uint8_t tank() const { return fluids; }
  SPATE_HD std::uint8_t solid(int k) const { return static_cast<std::uint8_t>(fluids + 1 + k); }
  // The fluid whose equation of state gives a wall particle its density (Adami): the reference.
  SPATE_HD const FluidMaterial& wall_fluid() const { return fluid[reference]; }
  SPATE_HD bool multiphase() const { return fluids > 1; }
  // The properties of fluid material m (m < fluids).
  SPATE_HD const FluidMaterial& of(std::uint8_t m) const { return fluid[m]; }
};

// The `phase` array that snapshots and Catalyst get with several fluids: the fluid index of a
// fluid particle (its material), -1 for a wall or solid particle.
inline std::int8_t phase_of(std::uint8_t material, int fluids) {
  return material < fluids ? static_cast<std::int8_t>(material) : std::int8_t{-1};
}

}  // namespace spate
