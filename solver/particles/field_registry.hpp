#pragma once
// The registry of per-particle fields: every field a particle carries is declared once, in
// SPATE_PARTICLE_FIELDS below, with what it is and where it travels. Everything else is derived
// from that one line (after SPH-EXA's field-name tuples):
//   - the host storage (ParticleStore members, particle_store.hpp) and its generic view fields(),
//   - sorting and permutation, halo and migration packing (particle_pack.hpp, the slab arrays),
//   - checkpoint datasets (io/checkpoint.cpp, with the names below and a format version),
//   - snapshot and in-situ arrays (io/vtk_snapshot.cpp, sim/insitu.hpp, the Catalyst adaptor),
//   - the CUDA device arrays and their pointer struct (backend/cuda/device_arrays.cuh), with a
//     static_assert that host and device agree field by field,
//   - the CPU neighbour record (the fields flagged kNeighbour, backend/cpu/neighbour_select.hpp),
//   - bytes per particle (host and device).
// docs/design.md ("Adding a particle field") shows the steps: one line here, then its physics.
//
// This header is plain constexpr data (no std::vector), so nvcc and the physics headers include it.
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <type_traits>

namespace spate {

enum class FieldType : std::uint8_t { F32, U32, U8 };
constexpr std::size_t field_type_size(FieldType t) { return t == FieldType::U8 ? 1 : 4; }
// A scalar has one array; a vector one array per axis (dim of them; storage for 3).
enum class FieldShape : std::uint8_t { Scalar, Vector };
// What a field is to the time loop.
enum class FieldRole : std::uint8_t {
  State,    // evolves and defines the particle (position, velocity, density, id, material)
  Rate,     // time derivatives computed each step (checkpointed: the integrator's next "previous")
  History,  // the integrator's previous rates (swapped with the rates every step)
  Derived,  // recomputed from the state every step before use (pressure from density)
};

// Where a field travels. Bit flags of FieldSpec::flags.
enum FieldFlag : std::uint16_t {
  kMigrated = 1 << 0,    // moves with an owned particle that changes slab (and gathers to the writer)
  kCheckpointed = 1 << 1,  // part of the restartable state: one HDF5 dataset per component
  kGhost = 1 << 2,       // copied to halo ghosts and periodic images (a neighbour needs it)
  kRefreshed = 1 << 3,   // a ghost field that changes after the halo is built: sent again in refreshes
  kExported = 1 << 4,    // written to snapshots and handed to in-situ pipelines (zero copy on the CPU)
  kNeighbour = 1 << 5,   // packed into the CPU fluid pass's 32-byte neighbour record (floats only)
  kOptional = 1 << 6,    // only in the stores of runs that need it (OptionalFields, particle_store.hpp):
                         // a feature's field that every other run must not pay for
  kThermal = 1 << 7,     // optional too, in its own group: only in the stores of runs with heat
                         // transfer (physics/heat_transfer.hpp), which do not pay for kOptional's
  kTurbulence = 1 << 8,  // optional, its own group: only in the stores of runs with SPS turbulence
                         // (physics/turbulence.hpp)
  kWallFrame = 1 << 9,   // optional, its own group: only in the stores of runs whose shaped walls slide
                         // or follow the log law (physics/wall_boundary.hpp WallFrame)
  kShiftVelocity = 1 << 10,  // optional, its own group: only in the stores of runs whose shifting
                             // corrects the velocity (`shifting.correct_velocity`, physics/shifting.hpp)
};
// The groups of optional fields (OptionalFields): a field in a group is in the stores of the runs
// that enable that group and no others.
constexpr std::uint16_t kOptionalGroups = kOptional | kThermal | kTurbulence | kWallFrame | kShiftVelocity;

struct FieldSpec {
  std::string_view member;  // C++ member of ParticleStore / DeviceFields
  FieldType type;
  FieldShape shape;
  FieldRole role;
  std::uint16_t flags;
  std::string_view exported;     // array name in snapshots and in situ ("" when not exported)
  std::string_view names[3];     // checkpoint dataset name of each component (scalars: names[0])
  constexpr bool has(std::uint16_t f) const { return (flags & f) == f; }
  // No flag: per-step scratch, written after the cell sort and read before the next one (the
  // shifting displacement): never permuted, moved, sent or saved.
  constexpr bool scratch() const { return flags == 0; }
  constexpr int components(int dim) const { return shape == FieldShape::Vector ? dim : 1; }
  constexpr std::size_t elem_size() const { return field_type_size(type); }
};

template <class T>
constexpr FieldType field_type_of() {
  static_assert(sizeof(T) == 1 || sizeof(T) == 4, "fields are 1 or 4 bytes wide (the sort's scratch word is 4 bytes)");
  if constexpr (sizeof(T) == 1) return FieldType::U8;
  else if constexpr (std::is_floating_point_v<T>) return FieldType::F32;
  else return FieldType::U32;
}

// F(member, C++ type, shape, role, flags, exported name, dataset name(s) ...)
// `shift`: the particle-shifting displacement (physics/shifting.hpp), between the fluid rates and
// the corrector of one step; sent to the ghosts, whose shifts the volume-consistent density reads
// (`shifting.volume_consistent`). `density_gradient`: the renormalised
// density gradient of `density.diffusion: antuono` (physics/density_gradient.hpp), sent to ghosts.
// `temperature` [K] and its rates: heat transfer (physics/heat_transfer.hpp), integrated like the
// density (predicted, corrected) for fluids and conducting walls; imposed by the wall temperature
// pass for the faces that take a condition. `temperature_residual`: what the compensated (Kahan)
// sum of the temperature's increments has not yet added (integrator.hpp compensated_add): a float
// at 300 K resolves 3e-5 K, and a slow approach to a steady state, whose increments per step fall
// below that, would otherwise stall short of it. The wall pass also sets `conductivity`, the k
// each particle conducts with (its own, or the mirrored material's behind a tank face; its
// neighbours read it, so it is sent to ghosts; saved with snapshots and checkpoints, so that
// `spate post` evaluates a heat-flux probe as the run did).
// `sps_stress`, `sps_shear`: the SPS stress over density T = tau / rho of `turbulence: {model: sps}`
// (physics/turbulence.hpp), diagonal (xx, yy, zz) and shear (xy, xz, yz; in 2D xy alone, the second
// component unused), sent to ghosts; `eddy_viscosity` nu_t [m^2/s], exported.
// `wall_normal`, `wall_depth`: the surface a shaped wall's particle lies under (the unit normal from
// the wall into the fluid, the particle's distance behind the surface), from the shape's signed
// distance at generation (case/generator.cpp), for free slip and the log law on faces that are not
// a box tank's (physics/wall_boundary.hpp WallFrame); the normal is sent to ghosts (the artificial
// viscosity lets a free-slip neighbour slide) and exported (to check it in ParaView).
// `temperature_gradient`: per-step scratch of the heat pass when particles are shifted (the corrector
// carries the temperature to the shifted position, T += grad T . dr). `shift_velocity`: per-step
// scratch of the shifting pass with `shifting.correct_velocity`, the velocity's change (grad v) dr
// at the shifted position, added by the corrector.
// Order matters only for readability and the neighbour record layout (kNeighbour fields in this
// order). Renaming a dataset is a checkpoint format change (kCheckpointFormatVersion, checkpoint.cpp).
// clang-format off
#define SPATE_PARTICLE_FIELDS(F)                                                                                       \
  F(pos, float, Vector, State, kMigrated | kCheckpointed | kGhost | kExported | kNeighbour, "Points", "x", "y", "z")  \
  F(vel, float, Vector, State, kMigrated | kCheckpointed | kGhost | kRefreshed | kExported | kNeighbour, "velocity",  \
    "vx", "vy", "vz")                                                                                                  \
  F(density, float, Scalar, State, kMigrated | kCheckpointed | kGhost | kRefreshed | kExported | kNeighbour,          \
    "density", "density")                                                                                              \
  F(pressure, float, Scalar, Derived, kMigrated | kGhost | kRefreshed | kExported | kNeighbour, "pressure", "pressure") \
  F(id, std::uint32_t, Scalar, State, kMigrated | kCheckpointed | kGhost | kExported, "id", "id")                     \
  F(material, std::uint8_t, Scalar, State, kMigrated | kCheckpointed | kGhost | kExported, "kind", "material")       \
  F(acc, float, Vector, Rate, kMigrated | kCheckpointed, "", "ax", "ay", "az")                                        \
  F(density_rate, float, Scalar, Rate, kMigrated | kCheckpointed, "", "density_rate")                                 \
  F(acc_prev, float, Vector, History, kMigrated, "", "ax_prev", "ay_prev", "az_prev")                                 \
  F(density_rate_prev, float, Scalar, History, kMigrated, "", "density_rate_prev")                                    \
  F(colour_gradient, float, Vector, Derived, kGhost | kRefreshed | kOptional, "", "colour_gradient_x",               \
    "colour_gradient_y", "colour_gradient_z")                                                                         \
  F(shift, float, Vector, Derived, kGhost | kRefreshed | kOptional, "", "sx", "sy", "sz")                             \
  F(density_gradient, float, Vector, Derived, kGhost | kRefreshed | kOptional, "", "density_gradient_x",             \
    "density_gradient_y", "density_gradient_z")                                                                       \
  F(temperature, float, Scalar, State, kMigrated | kCheckpointed | kGhost | kRefreshed | kExported | kThermal,        \
    "temperature", "temperature")                                                                                     \
  F(temperature_residual, float, Scalar, State, kMigrated | kCheckpointed | kThermal, "", "temperature_residual")    \
  F(temperature_rate, float, Scalar, Rate, kMigrated | kCheckpointed | kThermal, "", "temperature_rate")              \
  F(temperature_rate_prev, float, Scalar, History, kMigrated | kThermal, "", "temperature_rate_prev")              \
  F(conductivity, float, Scalar, Derived, kGhost | kRefreshed | kExported | kThermal, "conductivity", "conductivity")          \
  F(temperature_gradient, float, Vector, Derived, kThermal, "", "temperature_gradient_x", "temperature_gradient_y",     \
    "temperature_gradient_z")                                                                                         \
  F(sps_stress, float, Vector, Derived, kGhost | kRefreshed | kTurbulence, "", "sps_stress_xx", "sps_stress_yy",      \
    "sps_stress_zz")                                                                                                  \
  F(sps_shear, float, Vector, Derived, kGhost | kRefreshed | kTurbulence, "", "sps_stress_xy", "sps_stress_xz",       \
    "sps_stress_yz")                                                                                                  \
  F(eddy_viscosity, float, Scalar, Derived, kExported | kTurbulence, "eddy_viscosity", "eddy_viscosity")               \
  F(wall_normal, float, Vector, State, kMigrated | kCheckpointed | kGhost | kExported | kWallFrame, "wall_normal",    \
    "wall_normal_x", "wall_normal_y", "wall_normal_z")                                                                \
  F(wall_depth, float, Scalar, State, kMigrated | kCheckpointed | kWallFrame, "", "wall_depth")                     \
  F(shift_velocity, float, Vector, Derived, kShiftVelocity, "", "shift_velocity_x", "shift_velocity_y",               \
    "shift_velocity_z")
// clang-format on

#define SPATE_FIELD_SPEC(member, ctype, shape, role, flags, exported, ...) \
  FieldSpec{#member, field_type_of<ctype>(), FieldShape::shape, FieldRole::role, static_cast<std::uint16_t>(flags), exported, {__VA_ARGS__}},
inline constexpr FieldSpec kParticleFields[] = {SPATE_PARTICLE_FIELDS(SPATE_FIELD_SPEC)};
#undef SPATE_FIELD_SPEC

// Field numbers in registry order: kField_pos, kField_vel, ...
#define SPATE_FIELD_INDEX(member, ...) kField_##member,
enum FieldIndex : int { SPATE_PARTICLE_FIELDS(SPATE_FIELD_INDEX) kBuiltinFieldCount };
#undef SPATE_FIELD_INDEX

// The CPU neighbour record: the kNeighbour fields in registry order, 3 floats per vector (the
// third 0 in 2D), one 32-byte record per candidate (an 8 x 8 AVX2 transpose gathers 8 of them).
constexpr int neighbour_record_offset(int field) {
  int at = 0;
  for (int f = 0; f < field; ++f)
    if (kParticleFields[f].has(kNeighbour)) at += kParticleFields[f].shape == FieldShape::Vector ? 3 : 1;
  return kParticleFields[field].has(kNeighbour) ? at : -1;
}
constexpr int neighbour_record_floats() {
  int n = 0;
  for (const FieldSpec& f : kParticleFields)
    if (f.has(kNeighbour)) n += f.shape == FieldShape::Vector ? 3 : 1;
  return n;
}
static_assert(neighbour_record_floats() <= 8, "the CPU neighbour record holds 8 floats (one 32-byte AVX2 row)");
static_assert([] {
  for (const FieldSpec& f : kParticleFields)
    if (f.has(kNeighbour) && f.type != FieldType::F32) return false;
  return true;
}(), "only float fields can be packed into the neighbour record");
static_assert([] {
  for (const FieldSpec& f : kParticleFields)
    if (f.has(kRefreshed) && !f.has(kGhost)) return false;
  return true;
}(), "a refreshed field must be a ghost field");

// Bytes one particle's fields take in every run (every field but the optional groups', dim
// components per vector).
constexpr std::size_t builtin_field_bytes(int dim) {
  std::size_t b = 0;
  for (const FieldSpec& f : kParticleFields)
    if ((f.flags & kOptionalGroups) == 0) b += static_cast<std::size_t>(f.components(dim)) * f.elem_size();
  return b;
}

}  // namespace spate
