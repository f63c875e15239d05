#pragma once
// A simulation case as read from YAML (schema in docs/cases.md). Plain data; the loader validates
// it, the generator turns it into particles, physics_params() into the pair-loop constants.
#include <array>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "../physics/params.hpp"
#include "motion.hpp"
#include "shape.hpp"

namespace spate {

// Bad input: names the file, the key and what was expected. The program exits with code 2.
struct CaseError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

using Vec3d = std::array<double, 3>;

struct Box {
  Vec3d min{0, 0, 0};
  Vec3d max{0, 0, 0};
};

// Heat transfer (the case's `heat:` section and the `thermal:` keys; physics/heat_transfer.hpp,
// docs/cases.md "Heat transfer"). A material's thermal properties; `given` when the case has them.
struct ThermalSpec {
  bool given = false;
  double conductivity = 0.0;   // k [W/(m K)]
  double specific_heat = 0.0;  // c_p [J/(kg K)]
  double density = 0.0;        // walls and solids: their density [kg/m3] (fluids: their rest density)
  double expansion = 0.0;      // fluids: beta [1/K] of the Boussinesq buoyancy
  std::optional<double> reference_temperature;  // fluids: T_ref [K] (default: heat.initial_temperature)
  std::optional<double> temperature;  // walls and solids: the starting temperature [K]
  bool fixed = false;          // solids: held at `temperature`
  // fluids: the viscosity against temperature, [T [K], mu [Pa s]] with T ascending (empty: the
  // fluid's constant `viscosity`)
  std::vector<std::array<double, 2>> viscosity;
};

// A tank face's thermal condition (`tank.thermal.faces`).
struct FaceThermalSpec {
  ThermalCondition kind = ThermalCondition::Conducting;  // Conducting: none given (the tank's default)
  double value = 0.0;  // temperature [K] or heat flux into the fluid [W/m2]
};

// An initial temperature: `mean` plus an optional sinusoid along `axis` (amplitude, wavelength),
// T = mean + amplitude sin(2 pi (x_axis - origin) / wavelength), origin the tank's lower corner.
struct TemperatureField {
  double mean = 0.0;
  double amplitude = 0.0;
  double wavelength = 0.0;
  int axis = 0;
};

// A block of one fluid (at rest at t = 0 unless it has a velocity): a box, or a disc (2D) / sphere (3D) when `radius` > 0
// (min and max are then its bounding box), optionally with a sinusoidal top face. Where blocks
// overlap, the first listed holds the site (a bubble listed before the water around it).
struct FluidBlock : Box {
  int fluid = 0;               // index into Case::fluids
  Vec3d centre{0, 0, 0};       // disc/sphere centre
  double radius = 0.0;         // > 0: a disc/sphere instead of a box
  // top_wave: the top face at max_v + amplitude sin(2 pi (x - min_x) / wavelength) (0: flat).
  double wave_amplitude = 0.0;
  double wavelength = 0.0;
  // top_wave.start: false (`cut`) the lattice is cut at the wavy face; true (`displace`) it is cut
  // flat at max_v and every fluid particle is moved by the face's linear (potential-flow) mode,
  // which places the interface to a fraction of dp (generator.cpp, displace_by_waves).
  bool wave_displaces = false;
  std::optional<TemperatureField> temperature{};  // heat transfer: the block's (default: heat.initial_temperature)
  // The fluid's velocity at t = 0: uniform, or (`velocity_profile: parabolic`) a plane Poiseuille
  // profile across the block's height, `velocity` at mid-height and 0 at its bottom and top.
  Vec3d velocity{0, 0, 0};
  bool parabolic = false;
  // A region of any shape (mesh, polygon, polyhedron, cylinder; shape.hpp): the sites inside it,
  // less those under or within dp/2 of a shaped solid; min and max its bounding box.
  ShapePtr shape{};
};

struct SolidSpec {
  std::string name;
  Box box;  // the solid, or the bounding box of its shape
  bool hollow = true;  // only `wall_layers` layers under its surface are particles
  // What its surface does to the fluid along it (`free_slip: true`, at rest or moving;
  // `wall_shear: log_law`, at rest only): through each particle's own frame (params.hpp WallFrame).
  bool free_slip = false;
  WallShear wall_shear = WallShear::Laminar;
  // `wall_particles: surface`: its wall particles in layers parallel to its surface at the
  // lattice's spacing (shape.hpp surface_layers), not the lattice sites under it; the fluid keeps
  // kSurfaceClearance dp off its surface (generator.cpp).
  bool surface_particles = false;
  int motion = -1;     // index into Case::motions, or -1: static
  ThermalSpec thermal{};
  // A solid of any shape (mesh, cylinder, sphere/disc, polygon, polyhedron; shape.hpp), null for
  // the box: the lattice sites under its surface (generator.cpp).
  ShapePtr shape{};
};

// The points of a solid that can touch a plane first, at t = 0: of its surface (its shape's, or
// its box's corners), those farthest along each of a fan of directions (its convex hull's
// vertices, a curved surface's as facets; case_loader.cpp). A floating body's contact spheres sit
// there; a static or moving solid's press on the bodies' faces.
std::vector<Vec3d> solid_corners(const SolidSpec& solid, int dim);
// A solid's surface: its shape, or a box shape for a box solid.
ShapePtr solid_surface(const SolidSpec& solid, int dim);

// A solid the water moves (`motion: floating`, issue 32; sim/rigid_bodies.*): a rigid
// body of Simbody's whose load each step is the fluid's force (pressure and viscous) on its particles plus gravity.
struct BodySpec {
  int solid = -1;                  // index into Case::solids
  double mass = 0.0;               // [kg] (2D: per metre of depth)
  Vec3d centre_of_mass{0, 0, 0};   // at t = 0 [m]
  // About the centre of mass, world axes at t = 0: Ixx, Iyy, Izz, Ixy, Ixz, Iyz [kg m2] (2D: Izz per metre).
  std::array<double, 6> inertia{0, 0, 0, 0, 0, 0};
  // The degrees of freedom left free: x, y, z, rx, ry, rz (2D: x, y and rz); a locked one holds its
  // speed at zero (docs/cases.md, "Floating solids").
  std::array<bool, 6> free{true, true, true, true, true, true};
  // A hinge (`hinge:`): the body turns about `axis` (2D: z) through `point` and nothing else, held
  // by a rotational spring and damper [N m/rad, N m s/rad] (2D: per metre) about its start angle.
  struct Hinge {
    bool on = false;
    Vec3d point{0, 0, 0}, axis{0, 0, 1};
    double stiffness = 0.0, damping = 0.0;
  } hinge;
  // Linear springs and mooring lines (`springs:`) from a point of the body (at t = 0) to a fixed
  // anchor: tension k (L - length) + c dL/dt along the line [N/m, N s/m] (2D: per metre); a `slack`
  // line (a mooring) only pulls, and only when longer than its length.
  // With `to` (another floating solid, earlier in the case's list) the anchor is a point of that
  // body (at t = 0) and the line pulls both.
  struct Spring {
    Vec3d point{0, 0, 0}, anchor{0, 0, 0};
    double stiffness = 0.0, damping = 0.0, length = 0.0;
    bool slack = false;
    int to = -1;  // the other body (index into Case::bodies), or -1: a fixed anchor
  };
  std::vector<Spring> springs;
  // Contact with the tank's walls (`contact:`; Simbody's Hunt-Crossley compliant contact, docs/cases.md
  // "Floating solids"): on unless `contact: false` or the tank moves. `penetration`: the depth [m]
  // at which one contact point carries the body's weight (the stiffness follows); `dissipation`:
  // Hunt & Crossley's c [s/m] (restitution about 1 - c v at impact speed v); `friction`: Coulomb's
  // coefficient against the walls.
  // `points`: where its contact spheres sit, relative to the centre of mass at t = 0 (the loader's
  // solid_corners: the surface points farthest along a fan of directions).
  // `edges` (3D): spheres along its sharp edges, dp/2 apart (sharp_edge_points), which meet the
  // solids and the other bodies (an edge across an edge or a face), not the tank's planes.
  struct Contact {
    bool on = true;
    double penetration = 0.0, dissipation = 0.5, friction = 0.5;
    std::vector<Vec3d> points, edges;
  } contact;
};

enum class ProbeType { Pressure, Velocity, Height, Force, Front, WallPressure, Centroid, Temperature, HeatFlux, Interface, Body, Drive };

struct ProbeSpec {
  std::string name;
  ProbeType type = ProbeType::Pressure;
  Vec3d position{0, 0, 0};  // pressure/velocity: the point; height: the gauge (x, y) in 3D, (x) in 2D;
                            // wall_pressure: the centre of the sensing disc, on a wall or solid face
  std::string solid;        // force, body: the solid's name
  int face = -1;            // force, heat_flux: -1 the whole solid, else one face: 2 axis + (0 lower, 1 upper side)
  bool viscous = false;     // force: also the viscous part (columns f<axis>_viscous)
  int axis = 0;             // front: the axis along which the front advances
  Vec3d normal{0, 0, 0};    // wall_pressure: unit normal of the face, pointing into the fluid
  double diameter = 0.0;    // wall_pressure: diameter of the sensing disc [m] (0: a point)
  double window = 0.0;      // wall_pressure: moving-average window [s] (0: none)
  bool connected = false;   // height: the top of the water column standing on the floor (spray above ignored)
  double min_depth = 0.0;   // front: only water at least this deep counts (a bore over a wet bed)
  int follow = -1;          // pressure, velocity, height: moves with this motion (Case::motions), -1: fixed
  // pressure, velocity, height, centroid: only this fluid's particles (index into Case::fluids;
  // -1: every fluid); interface: the fluid whose volume fraction marks the interface (required);
  // `phase_name` its name, for descriptions.
  int phase = -1;
  std::string phase_name;
  // heat_flux: the Nusselt number q L / (k dT) beside the flux when length and temperature_difference
  // are given (k: `conductivity`, default the first fluid's).
  double length = 0.0;
  double temperature_difference = 0.0;
  double conductivity = 0.0;
};

// A fluid (a material, physics/materials.hpp): the case's `fluid:` section, or each entry of its
// `fluids:` list (several phases); fluid blocks and the wet bed name theirs (the first by default).
struct FluidSpec {
  std::string name = "water";
  double density = 1000.0;               // rest density rho0 [kg/m3]
  double viscosity = 1.0e-3;             // dynamic viscosity [Pa s]
  std::optional<double> sound_speed;     // empty: automatic, 10 sqrt(g H)
  double tait_exponent = 7.0;            // gamma of eq. 9
  double background_pressure = 0.0;      // [Pa], added to the Tait pressure
  ThermalSpec thermal{};                 // heat transfer: k, c_p, beta, T_ref
};

// A surface-tension coefficient between two fluids (an entry of the case's `surface_tension:`
// list, physics/surface_tension.hpp).
struct SurfaceTensionSpec {
  int a = 0, b = 1;      // indices into Case::fluids, a != b
  double coefficient = 0.0;  // sigma [N/m]
};

struct Case {
  std::string file;  // where it came from, for messages
  std::string name;
  std::string source_yaml;  // the effective YAML (after --set), stored in checkpoints
  int dim = 3;
  double dp = 0.01;
  double smoothing_ratio = 1.3;
  KernelType kernel = KernelType::WendlandC2;

  std::vector<FluidSpec> fluids{FluidSpec{}};  // material k is fluids[k]
  std::vector<SurfaceTensionSpec> surface_tension;  // empty: no surface tension
  // Heat transfer: on with a `heat:` section; every particle starts at initial_temperature unless
  // its block, the tank or its solid says otherwise.
  bool heat = false;
  double initial_temperature = 293.15;  // [K]
  // The gravity of the Boussinesq buoyancy (heat.gravity; default: the case's). A closed, full tank
  // may leave gravity out of the momentum equation (gravity: 0) and keep it here: the flow is the
  // same, its pressure the departure from hydrostatic, and the sound speed need not carry the
  // hydrostatic head (docs/physics.md, "Heat transfer").
  Vec3d buoyancy_gravity{0, 0, 0};
  ThermalSpec tank_thermal;
  std::array<FaceThermalSpec, 6> tank_faces;  // 2 axis + side (0 lower, 1 upper)
  double artificial_viscosity = 0.0;
  double wall_artificial_viscosity = 1.0;  // the factor on alpha in fluid-wall pairs
  bool tension = true;  // false: fluid pressures clipped at 0 (eos.hpp fluid_pressure)
  bool wall_tension = false;  // true: wall pressures not clipped at 0 (wall_boundary.hpp finish_wall)
  // true: the walls' density from their pressure by seventh_root (eos.hpp), the same bits on every
  // device; false: the C library's powf (fluid.portable_eos).
  bool portable_eos = false;
  DensityMode density_mode = DensityMode::Continuity;
  DensityDiffusion diffusion = DensityDiffusion::Fourtakas;
  // density.closed_volume: the fluid fills its container; its volume is held (sim/closed_volume.hpp).
  bool closed_volume = false;
  double delta = 0.1;
  MomentumFlux flux = MomentumFlux::Central;
  double riemann_limiter = 3.0;
  bool pressure_difference = false;  // momentum.pressure_gradient: difference (several fluids)
  // Relaxation before t = 0 (sim/relax.hpp), key `relax`: iterations (0: none), the random offset
  // of the start lattice [dp] and the rate kappa of dr = -kappa h^2 sum (...) grad W V per iteration.
  int relax_steps = 0;
  double relax_perturbation = 0.2;
  double relax_rate = 0.1;
  // SPS turbulence (Dalrymple & Rogers 2006; physics/turbulence.hpp), key `turbulence`: `model: sps`
  // with the Smagorinsky constant C_s and the isotropic coefficient C_I.
  bool sps = false;
  double smagorinsky = 0.12;
  double sps_isotropic = 0.0066;
  // Particle shifting (delta-plus-SPH; physics/shifting.hpp), key `shifting`.
  bool shifting = false;
  double shifting_coefficient = 1.0;
  double shifting_mach = 0.1;
  bool shifting_volume_consistent = false;  // the density follows the shift (shifting.hpp)
  bool shifting_free_surface = true;        // the free-surface rules (false: a closed flow)
  bool shifting_correct_velocity = false;   // the velocity follows the shift (shifting.hpp)
  Vec3d gravity{0, 0, -9.81};
  Vec3d body_force{0, 0, 0};
  // `drive`: the body force along the periodic axes set every step so that the fluid's mean
  // velocity (over its particles) approaches `mean_velocity` with the time constant
  // `response_time` (sim/flow_drive.hpp): a periodic channel driven at a given flow rate.
  struct DriveSpec {
    bool on = false;
    Vec3d mean_velocity{0, 0, 0};
    std::array<bool, 3> axes{false, false, false};  // the driven (periodic) axes
    double response_time = 0.0;                     // 0: one step
  } drive;
  // `relaxation_zone`: a box where the fluid's velocity relaxes towards `velocity` (a plane
  // Poiseuille profile across the box's height when parabolic) with the time constant `time`
  // (PhysicsParams::zone); time 0: none.
  struct ZoneSpec : Box {
    Vec3d velocity{0, 0, 0};
    bool parabolic = false;
    double time = 0.0;
  } zone;

  double end_time = 1.0;
  std::optional<double> fixed_dt;  // empty: adaptive
  double cfl = 0.2;
  double density_min_ratio = 0.5, density_max_ratio = 2.0;  // sanity limits on rho/rho0

  // Tank: interior [origin, origin + size], wall_layers layers of wall particles outside it.
  // A shaped tank (tank.mesh, cylinder, ...): the interior is inside the shape, the walls the sites
  // within wall_layers dp outside its surface; origin and size its bounding box in whole dp.
  ShapePtr tank_shape{};
  Vec3d tank_origin{0, 0, 0};
  Vec3d tank_size{1, 1, 1};
  int wall_layers = 3;
  // A shaped tank's `wall_particles: surface`: its walls in layers parallel to its surface outside
  // it (shape.hpp surface_layers), as a solid's.
  bool tank_surface_particles = false;
  bool open_top = true;
  std::array<bool, 3> periodic{false, false, false};
  std::array<bool, 3> free_slip{false, false, false};  // tank walls normal to these axes are free-slip
  bool shaped_tank_free_slip = false;                   // a shaped tank's surface is free-slip (tank.free_slip: true)
  WallShear wall_shear = WallShear::Laminar;           // tank.wall_shear (wall_boundary.hpp)
  double headroom = 0.5;  // domain extends this fraction of the tank height above an open top
  // Fluid that leaves through the open top (over the walls, above the headroom) is removed; more
  // than this fraction of the fluid removed stops the run (exit 3).
  double max_removed_fraction = 0.05;

  int tank_motion = -1;  // index into `motions`, or -1: the tank stands still
  // Prescribed wall motions (motion.hpp), of the tank and of solids; at most kMaxMotions. A
  // floating solid takes a slot too (MotionSpec::floating), through which the kernels see it move.
  std::vector<MotionSpec> motions;
  std::vector<BodySpec> bodies;  // the floating solids, in the order of their solids

  std::vector<FluidBlock> fluid_blocks;
  double wet_bed = 0.0;  // depth of still water on the rest of the floor
  int wet_bed_fluid = 0; // its fluid (index into fluids)
  std::vector<SolidSpec> solids;
  std::vector<ProbeSpec> probes;

  double output_interval = 0.0;   // simulated seconds between snapshots; 0: none
  double probe_interval = 0.0;    // 0: every step
  int checkpoint_every = 0;       // steps; 0: only at the end
  int checkpoint_keep_last = 2;   // periodic checkpoints kept (the newest); 0: all
  int checkpoint_keep_every = 0;  // also keep every Nth periodic checkpoint (step a multiple of N x checkpoint_every); 0: none
  int balance_every = 100;        // steps between load-balancing passes
  bool balanced_start = true;     // first faces from the balancer (else equal column counts, as the paper)

  // In situ (section `insitu:`): Catalyst scripts, relative paths resolved against the case
  // file's folder, run every `insitu_every` steps; --pipeline/--insitu-every replace them.
  std::vector<std::string> insitu_pipelines;
  int insitu_every = 1;
  double insitu_timeout = 300.0;      // seconds a pipeline may take on one in-situ step
  double insitu_live_timeout = 15.0;  // seconds a Catalyst Live peer may take to answer the handshake
};

// Reads, applies `overrides` ("key.path=value"), validates. Throws CaseError.
Case load_case(const std::string& path, const std::vector<std::string>& overrides = {});
// Same from YAML text already in memory (checkpoints keep the case they ran).
Case parse_case(const std::string& yaml_text, const std::string& file_name,
                const std::vector<std::string>& overrides = {});

// Highest fluid column, for the automatic sound speed.
double highest_fluid_column(const Case& c);
// The sound speed of fluid k: given, or automatic.
double sound_speed(const Case& c, int fluid = 0);
PhysicsParams physics_params(const Case& c);
// Why the tank has no wall at face f (2 axis + side): not a face of a case of this dimension, a
// periodic axis, the open top; nothing when it has one.
std::optional<std::string> tank_wall_missing(const Case& c, int face);
// The tank's upper corner as its particles make it: its extents rounded to whole dp.
Vec3d particle_tank_max(const Case& c);
// Names of the materials of the case, by material index (fluids, then "tank", then the solids).
std::vector<std::string> material_names(const Case& c);

}  // namespace spate
