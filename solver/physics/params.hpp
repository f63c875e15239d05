#pragma once
// Physical and numerical constants of a run, in the form the pair loops want them (derived once
// from the case; plain data so that it can be passed by value to a CUDA kernel).
#include <cstdint>

#include "kernels.hpp"
#include "../particles/field_registry.hpp"
#include "vec.hpp"
#include "heat_transfer.hpp"
#include "materials.hpp"
#include "wall_motion.hpp"

namespace spate {

enum class DensityMode : std::uint8_t { Continuity, Summation };
// Riemann: the pressure diffusion of the acoustic Riemann solver's interface velocity (fluid_interactions.hpp).
// Antuono: delta-SPH with renormalised density gradients, in passes of its own (density_gradient.hpp).
enum class DensityDiffusion : std::uint8_t { None, MolteniColagrossi, Fourtakas, Riemann, Antuono };
// The pressure term of the momentum equation: central (p_i + p_j, eq. 7) or the interface pressure
// of a linearised Riemann solver with a low-dissipation limiter (Zhang, Hu & Adams 2017).
enum class MomentumFlux : std::uint8_t { Central, Riemann };
// The shear of the tank walls (tank.wall_shear, wall_boundary.hpp): the laminar term's no-slip
// shear, or the smooth-wall log law's turbulent shear (a wall function).
enum class WallShear : std::uint8_t { Laminar, LogLaw };

// Surface-tension coefficients between fluids (physics/surface_tension.hpp), from the case's
// `surface_tension:` list: sigma[a][b] = sigma[b][a] [N/m] (0 on the diagonal and for pairs not
// listed), largest[a] the largest coefficient of fluid a. `on` when any pair has one: only then do
// the two surface-tension passes run.
struct SurfaceTensionTable {
  bool on = false;
  float sigma[kMaxFluids][kMaxFluids] = {};
  float largest[kMaxFluids] = {};
};

// Particle shifting of the delta-plus-SPH model (shifting.hpp; case key `shifting`). Off: no
// shifting pass runs and the step is what it was without it.
struct ShiftingParams {
  bool enabled = false;
  float coefficient = 1.0f;  // C of shifting.hpp (Sun et al. 2017: 1)
  float mach = 0.1f;         // Ma = U / c0 of the flow's reference speed U
  float tensile = 0.2f;      // R of the tensile-instability term (Sun et al. 2017: 0.2; relaxation: 0)
  bool volume_consistent = false;  // the density follows the shift's volume change (shifting.hpp)
  bool free_surface = true;        // the free-surface rules apply (false: a closed flow, shifting.hpp)
  bool correct_velocity = false;   // the velocity follows the shift to first order (shifting.hpp)
};

// SPS turbulence (turbulence.hpp; case key `turbulence`). Off: no SPS fields, no SPS passes.
struct TurbulenceParams {
  bool on = false;
  float smagorinsky2 = 0.0f;  // (C_s Delta)^2 [m^2], Delta = dp
  float isotropic = 0.0f;     // (2/3) C_I Delta^2 [m^2]
};

struct PhysicsParams {
  int dim = 3;
  KernelType kernel = KernelType::WendlandC2;
  float dp = 0.01f;              // particle spacing [m]
  float h = 0.013f;              // smoothing length [m]; support is 2h
  float inv_h = 1.0f / 0.013f;
  float inv_h2 = 1.0f / (0.013f * 0.013f);
  float support2 = 4.0f * 0.013f * 0.013f;
  float kernel_norm = 0.0f;      // alpha_d / h^dim
  float gradient_norm = 0.0f;    // kernel_norm / lattice gradient moment (kernels.hpp)
  float eta2 = 0.01f * 0.013f * 0.013f;  // 0.01 h^2, keeps r_ij . gradW / (r^2 + eta^2) finite
  float artificial_viscosity = 0.0f;  // Monaghan alpha; 0 switches it off
  // The factor on alpha in fluid-wall pairs (fluid.wall_artificial_viscosity; DualSPHysics calls it
  // ViscoBoundFactor). Against a wall at rest the term damps approach and also acts as a friction
  // along the wall, whatever the laminar term's slip (docs/physics.md, "Walls").
  float wall_artificial_viscosity = 1.0f;
  float delta = 0.1f;            // density diffusion coefficient
  DensityDiffusion diffusion = DensityDiffusion::Fourtakas;
  MomentumFlux flux = MomentumFlux::Central;
  float riemann_limiter = 3.0f;  // eta of the Riemann solver's limiter beta = min(eta dU, c0)
  // momentum.pressure_gradient (several fluids): 0 `symmetric`, eq. 7's p_i + p_j; 1 `difference`,
  // p_j - p_i, which vanishes for a uniform pressure on any particle arrangement
  // (multiphase_interactions.hpp; docs/physics.md, "Several fluids").
  float pressure_difference = 0.0f;
  // false: fluid pressures are clipped at 0 and continuity densities at rho0 (fluid.tension;
  // eos.hpp fluid_pressure, integrator.hpp correct_density).
  bool tension = true;
  // true: the walls take the negative pressure the fluid around them implies (fluid.wall_tension;
  // wall_boundary.hpp finish_wall); false: clipped at 0, so that a wall does not hold a free surface.
  bool wall_tension = false;
  // The walls' density from their pressure (wall_boundary.hpp finish_wall) through seventh_root,
  // which rounds alike on every device, instead of powf (fluid.portable_eos; eos.hpp).
  bool portable_eos = false;
  DensityMode density_mode = DensityMode::Continuity;
  ShiftingParams shifting;
  TurbulenceParams turbulence;
  // Only the first `dim` components are used; the last used axis is vertical (y in 2D, z in 3D).
  float gravity[3] = {0.0f, 0.0f, -9.81f};
  float body_force[3] = {0.0f, 0.0f, 0.0f};  // extra acceleration on fluid (Poiseuille driving)
  // A relaxation zone (case key `relaxation_zone`; fluid_interactions.hpp, relax_in_zone): inside
  // the box [lo, hi] the fluid's velocity relaxes towards `velocity` (times 4 s (1 - s) across the
  // box's height when parabolic) at the rate inv_time: a += (u* - v) inv_time. inv_time 0: none.
  struct RelaxationZone {
    float lo[3] = {0.0f, 0.0f, 0.0f}, hi[3] = {0.0f, 0.0f, 0.0f};
    float velocity[3] = {0.0f, 0.0f, 0.0f};
    float inv_time = 0.0f;
    bool parabolic = false;
  } zone;
  // Rest density, mass, viscosity, sound speed, Tait exponent of every fluid; walls and solids
  // (materials.hpp). The pair terms read fluid properties from here, never from scalars.
  MaterialTable materials;
  SurfaceTensionTable surface_tension;
  // Heat transfer (heat_transfer.hpp; the case's `heat:` section): thermal properties per material,
  // the tank faces' conditions. Off: no temperature field, no thermal pass.
  HeatParams heat;
  // Free-slip tank walls (tank.free_slip, wall_boundary.hpp): bit k set for the walls normal to
  // axis k; the tank's fluid region [tank_lo, tank_hi] tells a tank wall particle's side.
  std::uint8_t free_slip_axes = 0;
  WallShear wall_shear = WallShear::Laminar;
  float tank_lo[3] = {0.0f, 0.0f, 0.0f};
  float tank_hi[3] = {0.0f, 0.0f, 0.0f};
  // Prescribed wall motions (wall_motion.hpp; MaterialTable::motion says which walls follow
  // which), set by the time loop before every step: the state at the time the rates are
  // evaluated, and the rigid map of the predictor.
  int motions = 0;
  MotionState motion[kMaxMotions];
  MotionStep motion_step[kMaxMotions];

  SPATE_HD bool is_fluid(std::uint8_t material) const { return materials.is_fluid(material); }
  SPATE_HD bool moving_walls() const { return motions > 0; }
  // Whether the pair terms see a velocity of some wall particles: moving walls (continuity and the
  // artificial viscosity, fluid_interactions.hpp boundary_velocity), or free-slip tank faces, which
  // slide with the fluid for the artificial viscosity (PairKinematics::vr_av). The pair loop's
  // MovingWalls (dispatch.hpp).
  SPATE_HD bool walls_have_velocity() const { return motions > 0 || free_slip_axes != 0 || materials.faces_slide; }
  // Whether some wall's laminar-term velocity departs from Adami's no slip (free slip, the log law):
  // only then does the wall pass find a wall particle's frame (apply_wall_shear).
  SPATE_HD bool walls_shear_otherwise() const {
    return free_slip_axes != 0 || wall_shear == WallShear::LogLaw || materials.face_frames;
  }
  // The motion wall material m follows, or null when it is static (and for fluids).
  SPATE_HD const MotionState* motion_of(std::uint8_t m) const {
    const int k = materials.motion[m];
    return k > 0 ? &motion[k - 1] : nullptr;
  }
};

// F of grad_i W_ij = F r_ij for a pair at squared distance r2 (exactly 0 beyond the support), for
// the pair terms that need nothing else of |r_ij| (PairKinematics, the colour gradient and shifting
// keep |r_ij| or q for other uses and call Kernel::gradient_factor themselves).
template <class Kernel>
SPATE_HD float kernel_gradient_factor(const PhysicsParams& P, float r2) {
  return Kernel::gradient_factor(sqrtf(r2) * P.inv_h, P.gradient_norm, P.inv_h2);
}

// The velocity of wall particle x of material m (zero for static walls).
template <int Dim>
SPATE_HD Vec<Dim> wall_velocity(const PhysicsParams& P, std::uint8_t m, const Vec<Dim>& x) {
  const MotionState* s = P.motion_of(m);
  return s ? rigid_velocity<Dim>(*s, x) : zero_vec<Dim>();
}

// The face of the tank a tank wall particle lies behind: the one axis along which it is outside the
// fluid region [tank_lo, tank_hi] (axis -1 inside it, in a corner, or not a tank particle), how far
// behind the face (depth) and which way the fluid is along that axis (+1 or -1).
struct TankFace {
  int axis = -1;
  float depth = 0.0f;
  float into_fluid = 0.0f;
};

template <int Dim>
SPATE_HD TankFace tank_face(const PhysicsParams& P, const Vec<Dim>& x_wall, std::uint8_t material) {
  TankFace f;
  if (material != P.materials.tank()) return f;
  for (int k = 0; k < Dim; ++k) {
    const float below = P.tank_lo[k] - x_wall[k], above = x_wall[k] - P.tank_hi[k];
    if (below <= 0.0f && above <= 0.0f) continue;
    if (f.axis >= 0) return TankFace{};  // a corner
    f.axis = k;
    f.depth = below > 0.0f ? below : above;
    f.into_fluid = below > 0.0f ? 1.0f : -1.0f;
  }
  return f;
}

// Whether `face` is a free-slip face (tank.free_slip).
SPATE_HD bool is_free_slip(const PhysicsParams& P, const TankFace& face) {
  return face.axis >= 0 && (P.free_slip_axes & (1u << face.axis));
}

// The surface a wall particle lies under, as the wall treatments beyond Adami's no slip need it
// (wall_boundary.hpp: free slip, the log law; fluid_interactions.hpp: a free-slip face sliding for
// the artificial viscosity): the unit normal n from the wall into the fluid, the particle's depth
// behind the surface, and what the face does. A box tank's face gives it from the particle's
// position (tank_face: n along the face's axis; corners stay no slip); a shaped tank's or solid's
// particle carries its own (the kWallFrame fields wall_normal and wall_depth, which the generator
// takes from the shape's signed distance, and which turn with a moving wall: turn_with_motion_step),
// so free slip and the log law follow a slanted or curved face although the particles stand on the
// lattice's staircase under it. `w`: the wall's velocity at the particle (wall_motion.hpp).
template <int Dim>
struct WallFrame {
  Vec<Dim> n = zero_vec<Dim>();
  float depth = 0.0f;
  FaceShear shear = FaceShear::NoSlip;
  Vec<Dim> w = zero_vec<Dim>();  // the wall's own velocity there (a moving wall's; zero at rest)
};

template <int Dim>
SPATE_HD WallFrame<Dim> box_tank_frame(const PhysicsParams& P, const Vec<Dim>& x_wall, std::uint8_t material) {
  WallFrame<Dim> frame;
  const TankFace face = tank_face<Dim>(P, x_wall, material);
  if (face.axis < 0) return frame;
  frame.n[face.axis] = face.into_fluid;
  frame.depth = face.depth;
  frame.shear = is_free_slip(P, face) ? FaceShear::FreeSlip : P.wall_shear == WallShear::LogLaw ? FaceShear::LogLaw : FaceShear::NoSlip;
  return frame;
}

// Wall particle w's frame (x_wall its position): its own when its material's face has a treatment
// (MaterialTable::face_shear), else its box tank face's.
template <int Dim, class Fields>
SPATE_HD WallFrame<Dim> wall_frame(const PhysicsParams& P, const Fields& f, std::uint32_t w, const Vec<Dim>& x_wall) {
  const std::uint8_t m = f.material[w];
  const FaceShear shear = P.materials.face_shear[m];
  if (shear == FaceShear::NoSlip) return box_tank_frame<Dim>(P, x_wall, m);
  WallFrame<Dim> frame;
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) frame.n[k] = f.wall_normal[k][w];
  frame.depth = f.wall_depth[w];
  frame.shear = shear;
  frame.w = wall_velocity<Dim>(P, m, x_wall);
  return frame;
}

// Antuono's diffusion runs (its two passes, physics/density_gradient.hpp) only with continuity:
// summation density has no diffusion term.
inline bool uses_antuono_diffusion(const PhysicsParams& P) {
  return P.diffusion == DensityDiffusion::Antuono && P.density_mode == DensityMode::Continuity;
}

// Whether a run needs the optional registry fields (kOptional: surface tension's colour gradient,
// shifting's displacement, the renormalised density gradient of Antuono's diffusion): the stores
// of such a run carry them (OptionalFields), no other run pays their bytes. One switch for all of
// them: a run with any of these features carries all.
inline bool needs_optional_fields(const PhysicsParams& P) {
  return P.surface_tension.on || P.shifting.enabled || uses_antuono_diffusion(P);
}

// The optional field groups a run carries (OptionalFields, particle_store.hpp, as a mask of
// kOptionalGroups): kOptional as above, kThermal (the temperature and its rates) with heat transfer,
// kTurbulence (the SPS stress, turbulence.hpp) with SPS turbulence, kWallFrame (each wall
// particle's surface frame) when a shaped wall slides or follows the log law.
inline std::uint16_t optional_field_groups(const PhysicsParams& P) {
  return static_cast<std::uint16_t>((needs_optional_fields(P) ? kOptional : 0) | (P.heat.on ? kThermal : 0) |
                                    (P.turbulence.on ? kTurbulence : 0) | (P.materials.face_frames ? kWallFrame : 0) |
                                    (P.shifting.enabled && P.shifting.correct_velocity ? kShiftVelocity : 0));
}

}  // namespace spate
