// The worker's side of the backend interface (StepKernels), checked on the CPU: a stand-in backend
// keeps its own copy of the particles, like a GPU does, and runs the CPU backend's topology and
// loops on that copy (the CPU backend itself works on the worker's host store). If the worker read
// the host store where it must ask the arrays, or forgot to bring the host mirror up to date, the
// run would differ from the plain CPU backend. The CUDA backend follows the same protocol; its own
// test (CudaBackend.*) needs a GPU and skips without one.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <memory>
#include <numeric>
#include <thread>
#include <utility>

#include "../source_dir.hpp"
#include "backend/cpu/cpu_backend.hpp"
#include "backend/cuda/device_plan.hpp"
#include "backend/pair_lanes.hpp"
#include "backend/particle_updates.hpp"
#include "backend/cuda/device_runtime.hpp"
#include "backend/cuda/halo_exchange.hpp"
#include "case/case.hpp"
#include "case/generator.hpp"
#include "comm/in_process_transport.hpp"
#include "domain/host_slab_arrays.hpp"
#include "case/motion.hpp"
#include "io/field_scale.hpp"
#include "physics/dispatch.hpp"
#include "sim/slab_worker.hpp"

namespace spate {
namespace {

// The CPU backend over arrays of its own, as a GPU keeps them: the worker runs the same SlabTopology
// (migration, sort, halo, refresh with the interior/boundary overlap) and the same loops, but the
// host store is only a mirror, filled when the worker's particles() are read. If the worker read
// the host store where it must ask the arrays, results would differ from the CPU backend's.
class ResidentKernels : public cpu::Kernels {
 public:
  // `poison`: the halo ghosts' Refresh fields are NaN while the interior pass runs; `poison_all`:
  // also while the boundary passes run (the check that the poison would show).
  explicit ResidentKernels(int dim, bool poison = false, bool poison_all = false)
      : cpu::Kernels(std::make_unique<PoisoningArrays>(dim, poison, poison_all)) {}
  const char* name() const override { return "resident"; }
  void fluid_rates_range(const CellGrid& g, const PhysicsParams& P, ParticleRange range) override {
    cpu::Kernels::fluid_rates_range(g, P, range);
    ++ranges;
  }
  ParticleStore& device_store() { return arrays().store(); }
  int ranges = 0;

 protected:
  // A pass as a device runs it: `body` once per owned particle with its cell coordinates, one
  // particle after the other.
  template <class Body>
  void per_owned_particle(const PhysicsParams& P, Body&& body) {
    ParticleStore& p = device_store();
    const CellGridView v = arrays().grid().view();
    const Lattice& L = arrays().grid().lattice();
    dispatch_kernel_dim(P, [&]<class Kernel, int Dim>() {
      for (std::size_t i = 0; i < p.owned(); ++i) {
        int g[3] = {0, 0, 0};
        for (int a = 0; a < Dim; ++a) g[a] = L.cell_of(p.pos[a][i], a);
        body.template operator()<Kernel, Dim>(v, p, static_cast<std::uint32_t>(i), g);
      }
    });
  }
  // The same for the fluid pass over `range`, with the pair loop's compile-time choices.
  template <class Body>
  void fluid_pass_per_particle(const PhysicsParams& P, ParticleRange range, Body&& body) {
    ParticleStore& p = device_store();
    const CellGridView v = arrays().grid().view();
    const Lattice& L = arrays().grid().lattice();
    dispatch_pair_loop(P, [&]<class Kernel, int Dim, bool Gamma7, bool Multiphase, bool MovingWalls, bool Riemann>() {
      for (std::size_t i = range.first; i < range.end(); ++i) {
        int g[3] = {0, 0, 0};
        for (int a = 0; a < Dim; ++a) g[a] = L.cell_of(p.pos[a][i], a);
        body.template operator()<Kernel, Dim, Gamma7, Multiphase, MovingWalls, Riemann>(v, p, static_cast<std::uint32_t>(i), g);
      }
    });
  }

  // Poisons the Refresh fields of the halo ghosts and of their images as soon as a refresh is
  // staged: whatever the interior pass reads of them is NaN, which then shows in the results.
  class PoisoningArrays final : public HostSlabArrays {
   public:
    PoisoningArrays(int dim, bool poison, bool poison_all) : HostSlabArrays(dim), poison_(poison), poison_all_(poison_all) {}
    void stage(Side side, FieldSet set, ParticleRange range, Shift shift) override {
      HostSlabArrays::stage(side, set, range, shift);
      if (poison_ && set == FieldSet::Refresh) poison_ghosts();
    }
    void refresh_images(ImagePart part) override {
      HostSlabArrays::refresh_images(part);
      if (poison_all_ && part == ImagePart::Halo) poison_ghosts();
    }

   private:
    void poison_ghosts() {
      for (auto& f : store().fields()) {
        if (!in_set(f, FieldSet::Refresh)) continue;
        float* v = reinterpret_cast<float*>(f.bytes());
        for (Side s : {kLeft, kRight})
          for (std::uint32_t slot : halo_slots(s)) v[slot] = NAN;
        for (int axis = 1; axis < 3; ++axis)
          for (std::uint32_t slot : image_targets(axis, ImagePart::Halo)) v[slot] = NAN;
      }
    }
    bool poison_, poison_all_;
  };
};

// The GPU's arithmetic on the CPU: the resident path with the per-particle fluid body of
// backend/particle_updates.hpp, particle after particle, each summing its neighbours in one
// sequence as a CUDA thread does (cuda_kernels.cu), where the CPU backend's fluid loop sums them
// into 16 lanes. Everything else is the same code in the same order (the wall and summation
// passes are the same bodies; sqrt and division are IEEE-rounded on both; only powf in
// tait_density may round differently on a GPU), so its distance to the CPU backend is what the
// GPU check's comparison with the CPU must allow (GpuOrder.*).
class GpuOrderKernels final : public ResidentKernels {
 public:
  explicit GpuOrderKernels(int dim) : ResidentKernels(dim, true) {}
  void fluid_rates_range(const CellGrid&, const PhysicsParams& P, ParticleRange range) override {
    fluid_pass_per_particle(P, range, [&]<class Kernel, int Dim, bool Gamma7, bool Multiphase, bool MovingWalls, bool Riemann>(
                                          const CellGridView& v, ParticleStore& p, std::uint32_t i, const int g[3]) {
      update_fluid_rates<Kernel, Dim, Gamma7, Multiphase, MovingWalls, Riemann>(P, v, p, i, g);
    });
  }
  // SPS turbulence: the per-particle bodies the CUDA kernels run (visiting order), for the CPU's
  // batched, lane-summed passes (sps_passes.cpp).
  void sps_stress(ParticleStore&, const CellGrid&, const PhysicsParams& P) override {
    per_owned_particle(P, [&]<class Kernel, int Dim>(const CellGridView& v, ParticleStore& p, std::uint32_t i, const int g[3]) {
      update_sps_stress<Kernel, Dim>(P, v, p, i, g);
    });
  }
  void sps_acceleration(ParticleStore&, const CellGrid&, const PhysicsParams& P) override {
    per_owned_particle(P, [&]<class Kernel, int Dim>(const CellGridView& v, ParticleStore& p, std::uint32_t i, const int g[3]) {
      add_sps_acceleration<Kernel, Dim>(P, v, p, i, g);
    });
  }
  // Heat transfer as the CUDA kernels' per-thread loop runs it: every wall temperature's fit and
  // every particle's conduction sum in visiting order (the CPU's: in lanes, fused into its passes).
  void wall_temperature(ParticleStore&, const CellGrid&, const PhysicsParams& P) override {
    per_owned_particle(P, [&]<class Kernel, int Dim>(const CellGridView& v, ParticleStore& p, std::uint32_t i, const int g[3]) {
      update_wall_temperature<Kernel, Dim>(P, v, p, i, g);
    });
  }
  void heat_rates(ParticleStore&, const CellGrid&, const PhysicsParams& P) override {
    per_owned_particle(P, [&]<class Kernel, int Dim>(const CellGridView& v, ParticleStore& p, std::uint32_t i, const int g[3]) {
      update_heat_rates<Kernel, Dim>(P, v, p, i, g);
    });
  }
};

// The GPU's half-warp schedule on the CPU: the resident path with the fluid pass run as the CUDA
// backend's HalfWarp team runs it (pair_lanes.hpp), its 16 lanes one after the other (HostLanes):
// the candidates tested 16 at a time, the in-support ones dealt to the lanes in order, the lanes
// added in order; SPS turbulence's two passes the same way; and the wall pass as the GPU runs it
// (update_wall_state per particle). The other passes are the same bodies on both. It must give the
// CPU backend's bits (PairLanes.*).
class HostLaneKernels final : public ResidentKernels {
 public:
  explicit HostLaneKernels(int dim) : ResidentKernels(dim, true) {}
  void fluid_rates_range(const CellGrid&, const PhysicsParams& P, ParticleRange range) override {
    fluid_pass_per_particle(P, range, [&]<class Kernel, int Dim, bool Gamma7, bool Multiphase, bool MovingWalls, bool Riemann>(
                                          const CellGridView& v, ParticleStore& p, std::uint32_t i, const int g[3]) {
      update_fluid_rates_in_lanes<Kernel, Dim, Gamma7, Multiphase, MovingWalls, Riemann>(P, v, p, i, g, HostLanes{});
    });
  }
  // SPS turbulence's two passes on HalfWarp teams, as the GPU runs them.
  void sps_stress(ParticleStore&, const CellGrid&, const PhysicsParams& P) override {
    per_owned_particle(P, [&]<class Kernel, int Dim>(const CellGridView& v, ParticleStore& p, std::uint32_t i, const int g[3]) {
      update_sps_stress_in_lanes<Kernel, Dim>(P, v, p, i, g, HostLanes{});
    });
  }
  void sps_acceleration(ParticleStore&, const CellGrid&, const PhysicsParams& P) override {
    per_owned_particle(P, [&]<class Kernel, int Dim>(const CellGridView& v, ParticleStore& p, std::uint32_t i, const int g[3]) {
      add_sps_acceleration_in_lanes<Kernel, Dim>(P, v, p, i, g, HostLanes{});
    });
  }
  // The GPU's wall pass: the per-particle body, each wall particle summing its in-support fluid
  // neighbours in visiting order (the CPU's batched pass selects and sums the same ones).
  void wall_state(ParticleStore&, const CellGrid&, const PhysicsParams& P) override {
    per_owned_particle(P, [&]<class Kernel, int Dim>(const CellGridView& v, ParticleStore& p, std::uint32_t i, const int g[3]) {
      update_wall_state<Kernel, Dim>(P, v, p, i, g);
    });
  }
  // Heat transfer: the wall temperatures' fits on half-warps (the fluid particles' conduction is in
  // the fluid pass above; the CPU's heat pass, inherited, is left with the walls that conduct).
  void wall_temperature(ParticleStore&, const CellGrid&, const PhysicsParams& P) override {
    per_owned_particle(P, [&]<class Kernel, int Dim>(const CellGridView& v, ParticleStore& p, std::uint32_t i, const int g[3]) {
      update_wall_temperature_in_lanes<Kernel, Dim>(P, v, p, i, g, HostLanes{});
    });
  }
};

// Every checkpoint field of every particle, ordered by id, after `steps` fixed steps on `slabs`
// in-process slabs, each with the kernels `make` gives it.
// `hook`, if given, edits each slab's particles once after prepare() (the resident backends' own
// store, else the host store); `removed` collects the ids removed through open sides.
using ParticleHook = std::function<void(ParticleStore&)>;
std::vector<std::vector<char>> run(const Case& c, int slabs, int steps, const std::function<std::unique_ptr<StepKernels>()>& make,
                                   std::vector<float>* dts = nullptr, int balance_every = 0, std::atomic<bool>* faulted = nullptr,
                                   const ParticleHook& hook = {}, std::vector<std::uint32_t>* removed = nullptr) {
  const Lattice L = make_lattice(c);
  const PhysicsParams P = physics_params(c);
  const OptionalFields optional_fields(FieldGroups{optional_field_groups(P)});  // as Simulation::run
  const ParticleStore initial = generate_particles(c);
  InProcessHub hub(slabs);
  std::vector<ParticleStore> finals(slabs);
  std::vector<std::vector<float>> step_sizes(slabs);
  std::vector<std::vector<std::uint32_t>> gone(slabs);
  auto body = [&](int s) {
    auto t = hub.endpoint(s, L.periodic[0]);
    SlabWorker w(L, P, *t);
    w.set_open_sides(open_sides(c));
    ResidentKernels* resident = nullptr;
    if (make) {
      auto k = make();
      resident = dynamic_cast<ResidentKernels*>(k.get());
      w.use_kernels(std::move(k));
    }
    w.take_share(initial, SlabLayout::uniform(L.cells[0], slabs));
    w.prepare(true);
    if (hook) hook(resident ? resident->device_store() : w.particles());
    // Moving walls: the rigid map of every step, as the time loop sets it (sim/simulation.cpp).
    const MotionSet motions(c.motions, c.dim);
    PhysicsParams moving = P;
    double time = 0.0;
    for (int k = 0; k < steps; ++k) {
      if (balance_every > 0 && k > 0 && k % balance_every == 0) w.rebalance(2);
      const float dt = static_cast<float>(t->min(w.local_time_step(TimeStepControl{})));
      step_sizes[s].push_back(dt);
      if (motions.size() > 0) {
        motions.set_step(moving, time, time + dt);
        w.set_params(moving);
      }
      time += dt;
      const auto fault = w.step(dt);
      gone[s].insert(gone[s].end(), w.removed_ids().begin(), w.removed_ids().end());
      if (fault) {  // a fault is collective: every slab stops here
        if (faulted) *faulted = true;
        else ADD_FAILURE() << "unstable at step " << k << ": particle " << fault->id << " " << fault->what;
        break;
      }
    }
    finals[s] = w.particles();
    finals[s].resize(finals[s].owned());
  };
  std::vector<std::thread> pool;
  for (int s = 0; s < slabs; ++s) pool.emplace_back(body, s);
  for (auto& th : pool) th.join();
  if (dts) *dts = step_sizes[0];
  if (removed) {
    removed->clear();
    for (auto& g : gone) removed->insert(removed->end(), g.begin(), g.end());
    std::sort(removed->begin(), removed->end());
  }
  ParticleStore all(c.dim);
  for (auto& f : finals)
    for (std::size_t i = 0; i < f.size(); ++i) all.append_from(f, i);
  std::vector<std::uint32_t> order(all.size());
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&](auto a, auto b) { return all.id[a] < all.id[b]; });
  all.permute(0, order);
  std::vector<std::vector<char>> out;
  for (auto& f : all.fields())
    if (f.has(kCheckpointed)) out.emplace_back(f.bytes(), f.bytes() + all.size() * f.elem_size);
  return out;
}

Case small_dam_break() {
  // The 2D dam break, shortened so that a few steps take milliseconds.
  return load_case(test::source_dir() + "/cases/dam_break_2d.yaml", {"tank.size=[0.16, 0.12]"});
}

// The cases scripts/gpu-check compares between GPU and CPU (the same files, overrides and steps):
// walls and a free surface, periodic x (halo copies that wrap), periodic y (images, and images of
// halo ghosts), summation density (a second refresh per step).
struct CheckedCase {
  std::string name;
  Case c;
  int steps;
};
// The sloshing tank rolling and swaying fast (no ramp), so that its walls cross cells and slab faces
// within a hundred steps; coarse, so that the steps are quick.
Case moving_walls_case() {
  return load_case(test::source_dir() + "/cases/sloshing_2d.yaml",
                   {"dp=0.02", "tank.motion.ramp=0", "tank.motion.period=0.3", "tank.motion.rotation=4", "tank.motion.translation=[0.02, 0]"});
}

// Particle shifting amplifies any difference tenfold, so another summation order leaves the
// tolerance (GpuOrder); the cases that must give the CPU's bits take it: the shifting pass, with
// the volume-consistent density the shifts' halo refresh and the density pass, and with the velocity
// correction the velocity gradient in the shifting pass.
std::vector<CheckedCase> shifting_cases() {
  const std::string dam_break = test::source_dir() + "/cases/dam_break_2d.yaml";
  return {{"shifting", load_case(dam_break, {"shifting.enabled=true"}), 300},
          {"shifting_volume", load_case(dam_break, {"shifting.enabled=true", "shifting.volume_consistent=true"}), 300},
          {"shifting_velocity", load_case(dam_break, {"shifting.enabled=true", "shifting.correct_velocity=true"}), 300}};
}

std::vector<CheckedCase> gpu_checked_cases() {
  auto load = [](const std::string& file, const std::vector<std::string>& overrides) {
    return load_case(test::source_dir() + "/cases/" + file, overrides);
  };
  return {
      {"dam_break", load("dam_break_2d.yaml", {}), 300},
      {"periodic_x", load("poiseuille_2d.yaml", {"tank.size=[1.8e-3, 1.0e-3]", "fluid_blocks=[{min: [0, 0], max: [1.8e-3, 1.0e-3]}]"}), 100},
      {"periodic_y",
       load("hydrostatic_3d.yaml",
            {"tank.size=[0.3, 0.2, 0.3]", "fluid_blocks=[{min: [0, 0, 0], max: [0.3, 0.2, 0.1]}]", "tank.periodic=[y]"}),
       50},
      {"summation", load("dam_break_2d.yaml", {"density.mode=summation"}), 100},
      {"moving_walls", moving_walls_case(), 100},
      {"riemann", load("dam_break_2d.yaml", {"density.diffusion=riemann", "momentum.flux=riemann", "fluid.tension=false"}), 300},
      // Antuono's diffusion: the density-gradient and diffusion passes.
      {"antuono", load("dam_break_2d.yaml", {"density.diffusion=antuono"}), 300},
      // Several fluids: the multiphase pair terms, the GPU's per-particle loop against the CPU's
      // batched one (oil over water, viscosities 50 times apart).
      {"two_fluids", load("two_layer_hydrostatic_2d.yaml", {"probes=[]"}), 100},
      // Surface tension: the colour-gradient and force passes (a bubble ten times lighter).
      {"surface_tension", load("bubble_rise_2d.yaml", {"probes=[]"}), 100},
      // SPS turbulence: the stress and divergence passes (CPU: batched and lane-summed).
      {"sps", load("dam_break_2d.yaml", {"turbulence.model=sps"}), 300},
      // A shaped free-slip wall: each wall particle's own frame (wall_normal, wall_depth) in the
      // wall pass and for the artificial viscosity's sliding face.
      {"free_slip_slope", load("free_slip_slope_2d.yaml", {"probes=[]"}), 300},
      // A free-slip disc turning (surface-following wall particles whose normals turn with it).
      {"turning_disc", load("turning_disc_2d.yaml", {"probes=[]", "solids=[{name: disc, disc: {centre: [0.15, 0.13], radius: 0.08}, "
                                                     "wall_particles: surface, free_slip: true, motion: {rotation: 30, period: 0.5}}]"}), 300},
      // The same disc under the log law, which acts on the flow relative to the turning wall.
      {"turning_disc_log_law", load("turning_disc_2d.yaml", {"probes=[]", "solids=[{name: disc, disc: {centre: [0.15, 0.13], radius: 0.08}, "
                                                             "wall_particles: surface, wall_shear: log_law, motion: {rotation: 30, period: 0.5}}]"}), 200},
      // A floating box (its load summed over its particles, its particles moved rigidly by the
      // multibody step, the wall pass seeing its velocity and acceleration).
      {"floating_box", load("floating_box_2d.yaml", {"probes=[]", "dp=0.02"}), 200},
      // A free-slip sphere turning in 3D, its wall particles sampled evenly on its level sets.
      {"turning_sphere", load("turning_sphere_3d.yaml", {"probes=[]", "dp=0.012", "fluid_blocks=[{min: [0, 0, 0], max: [0.2, 0.2, 0.18]}]",
                                                         "solids=[{name: ball, sphere: {centre: [0.1, 0.1, 0.09], radius: 0.06}, wall_particles: surface, "
                                                         "free_slip: true, motion: {rotation: 30, axis: [0, 1, 0], period: 0.5}}]"}), 60},
      // Heat transfer: buoyant convection between a hot and a cold face (the fluid pass's fused
      // conduction, the wall temperatures behind the faces mirrored from the fluid) ...
      {"heated_cavity", load("heated_cavity_2d.yaml", {"probes=[]", "fluid.thermal.expansion=2.6295e-3"}), 100},
      // ... a surge over a heated floor past an adiabatic end wall (water sliding along the faces,
      // so that the fit's gradient carries the nearest particle's temperature to the mirror point) ...
      {"heated_floor", load("dam_break_2d.yaml", {"heat.initial_temperature=300", "fluid.thermal={conductivity: 50, specific_heat: 4186}",
                                                  "tank.thermal.faces={y-: {temperature: 330}, x-: {heat_flux: 20000}}"}), 200},
      // ... and conjugate conduction into a solid that carries its own temperature (the walls'
      // fits over fluid and solid carriers, the solid's own conduction in the heat pass), under
      // gravity: the still case's field varies along x alone and its sums came out the same in
      // either order, which would test nothing.
      {"conduction", load("conduction_2d.yaml", {"probes=[]", "gravity=[0, -9.81]", "fluid.sound_speed=10"}), 100},
  };
}

// The largest difference of two run() results over every checkpoint field, as a fraction of the
// field's scale (io/field_scale.hpp); a material that differs counts as infinite.
struct ScaledDifference {
  double worst = 0.0;
  std::string field;
};
ScaledDifference scaled_difference(const Case& c, const std::vector<std::vector<char>>& a, const std::vector<std::vector<char>>& b) {
  const PhysicsParams P = physics_params(c);
  ScaledDifference d;
  ParticleStore layout(c.dim);
  std::size_t k = 0;
  for (auto& f : layout.fields()) {
    if (!f.has(kCheckpointed)) continue;
    const double scale = field_scale(f.name, P);
    double worst = a[k] == b[k] ? 0.0 : INFINITY;
    if (f.elem_size == 4 && scale > 0) {
      worst = 0.0;
      const auto* x = reinterpret_cast<const float*>(a[k].data());
      const auto* y = reinterpret_cast<const float*>(b[k].data());
      for (std::size_t i = 0; i < a[k].size() / sizeof(float); ++i) {
        const double e = std::isnan(x[i]) || std::isnan(y[i]) ? INFINITY : std::fabs(double{x[i]} - double{y[i]}) / scale;
        worst = std::max(worst, e);
      }
    }
    if (worst > d.worst) d = {worst, std::string(f.name)};
    ++k;
  }
  return d;
}

}  // namespace

// The device orchestration (SlabTopology over SlabArrays, the resident worker path) against the
// CPU backend, on the host twin of the device arrays: every checkpoint field bit for bit.
void expect_same(const std::vector<std::vector<char>>& a, const std::vector<std::vector<char>>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t f = 0; f < a.size(); ++f) EXPECT_TRUE(a[f] == b[f]) << "checkpoint field " << f;
}

TEST(ResidentTopology, ThePoisonedGhostsWouldShow) {
  // The poison of the interior-pass tests is effective: left in the halo ghosts for the boundary
  // passes too (which do read the halo), it makes the run fail the health check.
  const Case dam = small_dam_break();
  std::atomic<bool> faulted = false;
  run(dam, 3, 8, [&] { return std::make_unique<ResidentKernels>(dam.dim, true, true); }, nullptr, 0, &faulted);
  EXPECT_TRUE(faulted);
}

TEST(ResidentTopology, ReproducesTheCpuBackendOnOneTwoAndThreeSlabs) {
  const Case c = small_dam_break();
  for (int slabs : {1, 2, 3}) {
    SCOPED_TRACE(std::to_string(slabs) + " slabs");
    std::vector<float> dt_cpu, dt_res;
    const auto cpu = run(c, slabs, 12, nullptr, &dt_cpu);
    const auto res = run(c, slabs, 12, [&] { return std::make_unique<ResidentKernels>(c.dim, true); }, &dt_res);
    EXPECT_EQ(dt_cpu, dt_res);
    expect_same(cpu, res);
  }
}

// Walls that move (rigid maps in the predictor, wall velocity and acceleration in the wall pass and
// the fluid loop) on the device orchestration: the same bits as the CPU backend on 1 to 3 slabs, and
// the walls really moved.
TEST(ResidentTopology, MovingWallsMatchTheCpuBackend) {
  const Case c = moving_walls_case();
  for (int slabs : {1, 3}) {
    SCOPED_TRACE(std::to_string(slabs) + " slabs");
    std::vector<float> dt_cpu, dt_res;
    const auto cpu = run(c, slabs, 60, nullptr, &dt_cpu);
    const auto res = run(c, slabs, 60, [&] { return std::make_unique<ResidentKernels>(c.dim, true); }, &dt_res);
    EXPECT_EQ(dt_cpu, dt_res);
    expect_same(cpu, res);
  }
  // The tank's walls moved: the first field is x, ordered by id; particle 0 is a wall.
  const ParticleStore initial = generate_particles(c);
  ASSERT_FALSE(physics_params(c).is_fluid(initial.material[0]));
  const auto after = run(c, 1, 60, nullptr);
  float x0 = 0.0f;
  std::memcpy(&x0, after[0].data(), sizeof x0);
  EXPECT_NE(x0, initial.pos[0][0]);
}

// The impact options (Riemann pressure diffusion and flux with its wall term, no tension; issue 11)
// keep the project's guarantees: 1 and 3 slabs bit-identical, and the shared per-particle bodies the
// device runs (on the host twin) bit-identical to the CPU backend's batched loop.
TEST(ResidentTopology, RiemannOptionsAreSplitIndependentAndMatchTheCpuBackend) {
  const Case c = load_case(test::source_dir() + "/cases/dam_break_2d.yaml",
                           {"tank.size=[0.16, 0.12]", "density.diffusion=riemann", "momentum.flux=riemann", "fluid.tension=false"});
  const auto three = run(c, 3, 12, nullptr);
  expect_same(run(c, 1, 12, nullptr), three);
  expect_same(three, run(c, 3, 12, [&] { return std::make_unique<ResidentKernels>(c.dim, true); }));
}

// Antuono's delta-SPH diffusion (the renormalised density gradient, refreshed to the ghosts, then
// the diffusion pass): 1 and 3 slabs bit-identical, the device's orchestration (host twin) the CPU
// backend's bits, and a different answer from the default diffusion.
TEST(ResidentTopology, AntuonoDiffusionIsSplitIndependentAndMatchesTheCpuBackend) {
  const Case c = load_case(test::source_dir() + "/cases/dam_break_2d.yaml", {"tank.size=[0.16, 0.12]", "density.diffusion=antuono"});
  const auto three = run(c, 3, 12, nullptr);
  expect_same(run(c, 1, 12, nullptr), three);
  expect_same(three, run(c, 3, 12, [&] { return std::make_unique<ResidentKernels>(c.dim, true); }));
  EXPECT_NE(three, run(small_dam_break(), 3, 12, nullptr));
}

// Surface tension (the colour gradient, refreshed to the ghosts, then the force): 1 and 3 slabs
// bit-identical, and the device's orchestration (host twin) bit-identical to the CPU backend.
TEST(ResidentTopology, SurfaceTensionIsSplitIndependentAndMatchesTheCpuBackend) {
  const Case c = load_case(test::source_dir() + "/cases/bubble_rise_2d.yaml", {"probes=[]"});
  const auto three = run(c, 3, 12, nullptr);
  expect_same(run(c, 1, 12, nullptr), three);
  expect_same(three, run(c, 3, 12, [&] { return std::make_unique<ResidentKernels>(c.dim, true); }));
}

// SPS turbulence (the stress, refreshed to the ghosts, then its divergence): 1 and 3 slabs
// bit-identical, the device's orchestration (host twin) the CPU backend's bits, and a different
// answer from the laminar run.
TEST(ResidentTopology, SpsTurbulenceIsSplitIndependentAndMatchesTheCpuBackend) {
  const Case c = load_case(test::source_dir() + "/cases/dam_break_2d.yaml", {"tank.size=[0.16, 0.12]", "turbulence.model=sps"});
  const auto three = run(c, 3, 12, nullptr);
  expect_same(run(c, 1, 12, nullptr), three);
  expect_same(three, run(c, 3, 12, [&] { return std::make_unique<ResidentKernels>(c.dim, true); }));
  EXPECT_NE(three, run(load_case(test::source_dir() + "/cases/dam_break_2d.yaml", {"tank.size=[0.16, 0.12]"}), 3, 12, nullptr));
}

TEST(ResidentTopology, SummationDensityAndPeriodicXMatchTheCpuBackend) {
  const Case summation = load_case(test::source_dir() + "/cases/dam_break_2d.yaml",
                                   {"tank.size=[0.16, 0.12]", "density.mode=summation"});
  expect_same(run(summation, 3, 6, nullptr), run(summation, 3, 6, [&] { return std::make_unique<ResidentKernels>(2, true); }));
  // Periodic x: halo copies wrap with the period; one slab is its own neighbour.
  const Case channel = load_case(test::source_dir() + "/cases/poiseuille_2d.yaml", {});
  for (int slabs : {1, 2, 3}) {
    SCOPED_TRACE(std::to_string(slabs) + " slabs, periodic x");
    expect_same(run(channel, slabs, 6, nullptr), run(channel, slabs, 6, [&] { return std::make_unique<ResidentKernels>(2, true); }));
  }
}

TEST(ResidentTopology, PeriodicImagesIn3dMatchTheCpuBackend) {
  // Periodic y makes images of owned particles (refreshed before the interior pass) and of halo
  // ghosts (poisoned until the halo arrives).
  const Case c = load_case(test::source_dir() + "/cases/hydrostatic_3d.yaml",
                           {"tank.size=[0.3, 0.2, 0.3]", "fluid_blocks=[{min: [0, 0, 0], max: [0.3, 0.2, 0.1]}]", "tank.periodic=[y]"});
  for (int slabs : {1, 3}) {
    SCOPED_TRACE(std::to_string(slabs) + " slabs");
    expect_same(run(c, slabs, 4, nullptr), run(c, slabs, 4, [&] { return std::make_unique<ResidentKernels>(3, true); }));
  }
}

TEST(ResidentTopology, MovingFacesHandParticlesOverLikeTheCpuBackend) {
  const Case c = small_dam_break();
  auto resident = [&] { return std::make_unique<ResidentKernels>(c.dim); };
  expect_same(run(c, 3, 12, nullptr, nullptr, 3), run(c, 3, 12, resident, nullptr, 3));
}

TEST(ResidentTopology, TheInteriorPassIsUsedAndNeedsNoGhost) {
  // With poisoned ghosts a wrong interior (one that reads a ghost) gives NaN rates: the CPU
  // comparison above would fail. Here: the interior pass exists on slabs at least three columns wide.
  const Case c = small_dam_break();
  const Lattice L = make_lattice(c);
  ASSERT_GE(L.cells[0], 9);
  CellGrid grid;
  grid.configure(L, 0, L.cells[0]);
  std::vector<std::uint32_t> starts(L.cells[0] + 1);
  for (int k = 0; k <= L.cells[0]; ++k) starts[k] = 10u * k;
  const OwnedSplit s = plan_owned_split(grid, starts, true, true);
  EXPECT_EQ(s.before, (ParticleRange{0, 10}));
  EXPECT_EQ(s.interior, (ParticleRange{10, 10u * (L.cells[0] - 2)}));
  EXPECT_EQ(s.after.end(), 10u * L.cells[0]);
}

TEST(ResidentTopology, DeviceHealthAndDomainChecksFindTheHostsFault) {
  const Case c = small_dam_break();
  const Lattice L = make_lattice(c);
  const PhysicsParams P = physics_params(c);
  const OptionalFields optional_fields(FieldGroups{optional_field_groups(P)});  // as Simulation::run
  const ParticleStore initial = generate_particles(c);
  InProcessHub hub(1);
  auto t = hub.endpoint(0, L.periodic[0]);
  SlabWorker host(L, P, *t), dev(L, P, *t);
  auto kernels = std::make_unique<ResidentKernels>(c.dim);
  ParticleStore& device = kernels->device_store();
  dev.use_kernels(std::move(kernels));
  for (SlabWorker* w : {&host, &dev}) {
    w->take_share(initial, SlabLayout::uniform(L.cells[0], 1));
    w->prepare(true);
  }
  // Every fluid particle fails a density window below rho0: the lowest fluid id, same message.
  const auto a = host.health(0.5f, 0.9f), b = dev.health(0.5f, 0.9f);
  ASSERT_TRUE(a && b);
  EXPECT_EQ(a->id, b->id);
  EXPECT_EQ(a->what, b->what);
  EXPECT_FALSE(dev.health(0.5f, 2.0f));
  // Two fluid particles thrown out of the domain: the step stops at the lower id, host's message.
  auto throw_out = [](ParticleStore& p, std::uint32_t id, float v) {
    for (std::size_t i = 0; i < p.owned(); ++i)
      if (p.id[i] == id) p.vel[0][i] = v;
  };
  std::vector<std::uint32_t> fluid;
  for (std::size_t i = 0; i < device.owned(); ++i)
    if (MaterialTable{}.is_fluid(device.material[i])) fluid.push_back(device.id[i]);
  ASSERT_GE(fluid.size(), 2u);
  std::sort(fluid.begin(), fluid.end());
  for (ParticleStore* p : {&host.particles(), &device}) {
    throw_out(*p, fluid[fluid.size() / 2], 1e6f);
    throw_out(*p, fluid.back(), -1e6f);
  }
  const auto fa = host.step(1e-3f), fb = dev.step(1e-3f);
  ASSERT_TRUE(fa && fb);
  EXPECT_EQ(fa->id, fluid[fluid.size() / 2]);
  EXPECT_EQ(fa->id, fb->id);
  EXPECT_EQ(fa->what, fb->what);
}

// Fluid that leaves through the open top is removed, by whichever slab holds it, the same way on the
// CPU path and the device-resident one: thrown above the ceiling (top + headroom), or over a wall
// (above its top, past its outer face). The removed ids and every remaining particle agree bit for
// bit for 1, 2 and 3 slabs and both paths.
TEST(OpenSides, EscapedFluidIsRemovedTheSameWayOnEverySplitAndPath) {
  const Case c = small_dam_break();  // open top at y = 0.12 m, headroom 0.06 m, walls x in [-0.006, 0.166] m
  const OpenSides o = open_sides(c);
  ASSERT_TRUE(o.open);
  EXPECT_FLOAT_EQ(o.top, 0.12f);
  EXPECT_FLOAT_EQ(o.ceiling, 0.18f);
  EXPECT_NEAR(o.lo[0], -0.006f, 1e-7f);
  EXPECT_NEAR(o.hi[0], 0.166f, 1e-7f);
  const ParticleStore initial = generate_particles(c);
  std::vector<std::uint32_t> fluid;
  for (std::size_t i = 0; i < initial.size(); ++i)
    if (physics_params(c).is_fluid(initial.material[i])) fluid.push_back(initial.id[i]);
  ASSERT_GE(fluid.size(), 40u);
  const std::uint32_t up = fluid[3], up2 = fluid[fluid.size() - 5], over = fluid[fluid.size() / 2], stays = fluid[10];
  // (Placed, not thrown: a fast particle would shrink the adaptive step instead.) `up` and `up2`
  // above the ceiling, `over` past the right wall above its top, `stays` above the wall's top but
  // not past its face (it may fall back in).
  auto throw_out = [=](ParticleStore& p) {
    for (std::size_t i = 0; i < p.owned(); ++i) {
      if (p.id[i] == up || p.id[i] == up2) p.pos[1][i] = 0.182f;
      if (p.id[i] == over) p.pos[0][i] = 0.1665f, p.pos[1][i] = 0.13f;
      if (p.id[i] == stays) p.pos[0][i] = 0.163f, p.pos[1][i] = 0.125f;
      if (p.id[i] == up || p.id[i] == up2 || p.id[i] == over || p.id[i] == stays) p.vel[0][i] = p.vel[1][i] = 0.0f;
    }
  };
  std::vector<std::uint32_t> expected{up, up2, over};
  std::sort(expected.begin(), expected.end());
  std::vector<std::uint32_t> removed;
  const auto reference = run(c, 1, 6, nullptr, nullptr, 0, nullptr, throw_out, &removed);
  EXPECT_EQ(removed, expected);
  ASSERT_EQ(reference[0].size(), (initial.size() - 3) * sizeof(float)) << "three particles fewer";
  for (int slabs : {1, 2, 3}) {
    SCOPED_TRACE(std::to_string(slabs) + " slabs");
    expect_same(reference, run(c, slabs, 6, nullptr, nullptr, 0, nullptr, throw_out, &removed));
    EXPECT_EQ(removed, expected);
    expect_same(reference, run(c, slabs, 6, [&] { return std::make_unique<ResidentKernels>(c.dim, true); }, nullptr, 0, nullptr,
                               throw_out, &removed));
    EXPECT_EQ(removed, expected);
  }
}

// A swaying tank's open sides are its own: a splash is judged where the tank's walls are now, not
// where they stood at t = 0 (the tank 3 cm to the right: a drop 1 cm past the right wall's outer
// face at t = 0 is still above the wall; 4 cm past it, it is out; turned, its top is elsewhere).
TEST(OpenSides, ASwayingTanksSplashIsJudgedWhereItsWallsAreNow) {
  const Case c = small_dam_break();  // open top at y = 0.12 m, walls x in [-0.006, 0.166] m
  OpenSides o = open_sides(c);
  const float near_wall[3] = {0.176f, 0.13f, 0.0f}, far_out[3] = {0.206f, 0.13f, 0.0f}, left_out[3] = {-0.01f, 0.13f, 0.0f};
  EXPECT_TRUE(escaped(o, 2, 0, near_wall));
  EXPECT_TRUE(escaped(o, 2, 0, left_out));
  o.moving = true;
  EXPECT_TRUE(escaped(o, 2, 0, near_wall));  // the identity
  o.shift[0] = 0.03f;
  EXPECT_FALSE(escaped(o, 2, 0, near_wall));
  EXPECT_TRUE(escaped(o, 2, 0, far_out));
  o.shift[0] = -0.03f;  // to the left: the drop left of the left wall's place at t = 0 is above the tank
  EXPECT_FALSE(escaped(o, 2, 0, left_out));
  // Turned by 90 degrees about the tank's centre: the top is now to the left.
  o.shift[0] = 0.0f;
  o.centre[0] = 0.08f, o.centre[1] = 0.06f;
  o.back[0][0] = 0.0f, o.back[0][1] = 1.0f, o.back[1][0] = -1.0f, o.back[1][1] = 0.0f;  // R(-90 deg)
  const float beyond_top[3] = {0.08f - 0.19f, 0.06f, 0.0f};  // at t = 0: 0.19 m above the centre, over the ceiling
  EXPECT_TRUE(escaped(o, 2, 0, beyond_top));
  EXPECT_FALSE(escaped(o, 2, 0, far_out));
}

TEST(OpenSides, AParticleThroughAWallOrUnderAClosedLidIsStillAFault) {
  Case c = small_dam_break();
  const ParticleStore initial = generate_particles(c);
  std::uint32_t victim = 0;
  for (std::size_t i = 0; i < initial.size(); ++i)
    if (physics_params(c).is_fluid(initial.material[i])) victim = initial.id[i];
  // Out through the left wall, below its top: not an open side.
  auto through_wall = [=](ParticleStore& p) {
    for (std::size_t i = 0; i < p.owned(); ++i)
      if (p.id[i] == victim) p.pos[0][i] = -0.05f;
  };
  std::atomic<bool> faulted = false;
  std::vector<std::uint32_t> removed;
  run(c, 2, 3, nullptr, nullptr, 0, &faulted, through_wall, &removed);
  EXPECT_TRUE(faulted);
  EXPECT_TRUE(removed.empty());
  // Up through a closed lid.
  c = load_case(test::source_dir() + "/cases/dam_break_2d.yaml", {"tank.size=[0.16, 0.12]", "tank.open_top=false"});
  EXPECT_FALSE(open_sides(c).open);
  auto up = [=](ParticleStore& p) {
    for (std::size_t i = 0; i < p.owned(); ++i)
      if (p.id[i] == victim) p.pos[1][i] = 0.3f;
  };
  faulted = false;
  run(c, 1, 3, [&] { return std::make_unique<ResidentKernels>(c.dim); }, nullptr, 0, &faulted, up, &removed);
  EXPECT_TRUE(faulted);
  EXPECT_TRUE(removed.empty());
}

TEST(TimeStep, ANanParticleAllowsZeroWhereverItSits) {
  // A minimum built on `<` keeps or drops a NaN depending on where it meets it (OpenMP's partial
  // minima, CUB's reduction tree): a particle with a NaN speed allows 0 instead, so every order
  // gives 0 and the run stops with "the time step collapsed". A NaN acceleration gives a number
  // already (the sound-speed limit).
  const Case c = small_dam_break();
  const PhysicsParams P = physics_params(c);
  const TimeStepControl ctl;
  EXPECT_EQ(particle_time_step(P, P.materials.fluid[0], ctl, NAN, 1.0f), 0.0f);
  EXPECT_EQ(particle_time_step(P, P.materials.fluid[0], ctl, 1.0f, NAN), particle_time_step(P, P.materials.fluid[0], ctl, 1.0f, 0.0f));
  EXPECT_GT(particle_time_step(P, P.materials.fluid[0], ctl, 1.0f, 1.0f), 0.0f);
  const ParticleStore p = generate_particles(c);
  EXPECT_GT(cpu::min_time_step(p, P, ctl), 0.0f);
  for (std::size_t i = 0; i < p.owned(); i += p.owned() / 7) {
    if (!P.is_fluid(p.material[i])) continue;
    ParticleStore q = p;
    q.vel[0][i] = NAN;
    EXPECT_EQ(cpu::min_time_step(q, P, ctl), 0.0f) << "NaN velocity at " << i;
  }
}

TEST(GpuOrder, TheGpusSummationOrderStaysWellWithinTheGpuCheckTolerance) {
  // What the GPU-against-CPU comparisons must allow, measured on the CPU: the CPU backend against
  // the same run with the fluid loop summed as a CUDA thread sums (GpuOrderKernels), on the cases
  // and step counts of the GPU check. Within a quarter of kGpuCpuScaledTolerance, leaving room
  // for the device's powf; not zero, or the two orders would not differ and this measured nothing.
  for (const auto& k : gpu_checked_cases()) {
    SCOPED_TRACE(k.name);
    std::vector<float> dt_cpu, dt_gpu_order;
    const auto cpu = run(k.c, 1, k.steps, nullptr, &dt_cpu);
    const auto gpu_order = run(k.c, 1, k.steps, [&] { return std::make_unique<GpuOrderKernels>(k.c.dim); }, &dt_gpu_order);
    const ScaledDifference d = scaled_difference(k.c, cpu, gpu_order);
    EXPECT_LE(d.worst, gpu::kGpuCpuScaledTolerance / 4) << d.field;
    EXPECT_GT(d.worst, 0.0);
    ASSERT_EQ(dt_cpu.size(), dt_gpu_order.size());
    for (std::size_t n = 0; n < dt_cpu.size(); ++n) EXPECT_NEAR(dt_gpu_order[n], dt_cpu[n], gpu::kGpuCpuScaledTolerance / 4 * dt_cpu[n]);
  }
}

TEST(PairLanes, EachLaneTakesTheInSupportNeighbourOfItsNumberModuloSixteen) {
  // Every group of 16 candidates (each inside mask) after every count of earlier neighbours: the
  // lanes take the group's in-support candidates one each, neighbour n by lane n mod 16, in order.
  for (unsigned base = 0; base < 40; base += 3)
    for (unsigned inside = 0; inside < (1u << kPairLanes); inside += 7) {
      int taken = 0;
      for (int lane = 0; lane < kPairLanes; ++lane) {
        const int q = lane_candidate(inside, base, lane);
        if (q < 0) continue;
        ASSERT_TRUE((inside >> q) & 1u);
        const unsigned n = base + static_cast<unsigned>(__builtin_popcount(inside & ((1u << q) - 1u)));  // q's neighbour number
        ASSERT_EQ(n % kPairLanes, static_cast<unsigned>(lane)) << "inside " << inside << " base " << base;
        ++taken;
      }
      ASSERT_EQ(taken, __builtin_popcount(inside));
    }
}

TEST(PairLanes, TheGpusHalfWarpScheduleGivesTheCpusBits) {
  // The CUDA backend's fluid pass (HalfWarp, one lane per thread) emulated on the host with the
  // same body (HostLaneKernels) against the CPU backend, on every case the GPU check runs: every
  // checkpoint field and every time step bit for bit. So the GPU's results are the CPU's wherever
  // the device's arithmetic is IEEE: with fluid.portable_eos (the walls' inverse EOS by
  // seventh_root, not powf) and gamma 7. Shifting too, which amplifies any difference tenfold.
  auto cases = gpu_checked_cases();
  for (auto& k : shifting_cases()) cases.push_back(std::move(k));
  for (const auto& k : cases) {
    SCOPED_TRACE(k.name);
    std::vector<float> dt_cpu, dt_lanes;
    const auto cpu = run(k.c, 1, k.steps, nullptr, &dt_cpu);
    const auto lanes = run(k.c, 1, k.steps, [&] { return std::make_unique<HostLaneKernels>(k.c.dim); }, &dt_lanes);
    EXPECT_EQ(dt_cpu, dt_lanes);
    expect_same(cpu, lanes);
  }
}

// The real thing: the CUDA kernels against the CPU loops. Skips, visibly, on machines without a GPU
// (the CI machine has none; scripts/gpu-check runs them on one and fails if any is skipped).
namespace {
bool no_gpu() { return gpu::device_count() == 0; }
std::string why_no_gpu() { return std::string("no CUDA device (") + (gpu::built_with_cuda() ? "built with CUDA" : "built without CUDA") + ")"; }
auto cuda_kernels(int dim) {
  return [dim] { return gpu::make_cuda_kernels(0, dim); };
}
}  // namespace

TEST(CudaBackend, MatchesTheCpuBackendWithinTheGpuCheckTolerance) {
  if (no_gpu()) GTEST_SKIP() << why_no_gpu();
  for (const auto& k : gpu_checked_cases()) {
    SCOPED_TRACE(k.name);
    std::vector<float> dt_cpu, dt_gpu;
    const auto cpu = run(k.c, 1, k.steps, nullptr, &dt_cpu);
    const auto gpu = run(k.c, 1, k.steps, cuda_kernels(k.c.dim), &dt_gpu);
    const ScaledDifference d = scaled_difference(k.c, cpu, gpu);
    EXPECT_LE(d.worst, gpu::kGpuCpuScaledTolerance) << d.field;
    ASSERT_EQ(dt_cpu.size(), dt_gpu.size());
    for (std::size_t n = 0; n < dt_cpu.size(); ++n) EXPECT_NEAR(dt_gpu[n], dt_cpu[n], gpu::kGpuCpuScaledTolerance * dt_cpu[n]);
  }
}

TEST(CudaBackend, TheHalfWarpFluidPassGivesTheCpusBits) {
  // What PairLanes.TheGpusHalfWarpScheduleGivesTheCpusBits proves on the host, on the device: every
  // checked case gives the CPU backend's bits, time steps included, with fluid.portable_eos (the
  // walls' inverse EOS by seventh_root, which rounds alike on both; powf's last bit is the library's).
  if (no_gpu()) GTEST_SKIP() << why_no_gpu();
  auto cases = gpu_checked_cases();
  for (auto& k : shifting_cases()) cases.push_back(std::move(k));
  for (const auto& k : cases) {
    SCOPED_TRACE(k.name);
    Case c = k.c;
    c.portable_eos = true;
    std::vector<float> dt_cpu, dt_gpu;
    const auto cpu = run(c, 1, k.steps, nullptr, &dt_cpu);
    const auto gpu = run(c, 1, k.steps, cuda_kernels(c.dim), &dt_gpu);
    EXPECT_EQ(dt_cpu, dt_gpu);
    expect_same(cpu, gpu);
  }
}

TEST(CudaBackend, ThreeSlabsGiveTheSameAnswerAsOneOnTheGpu) {
  // Every checked case on three workers sharing GPU 0 (same-device links) against one worker: bit
  // for bit, time steps included. Fewer steps than the CPU comparison: any difference is a bug.
  if (no_gpu()) GTEST_SKIP() << why_no_gpu();
  for (const auto& k : gpu_checked_cases()) {
    SCOPED_TRACE(k.name);
    const int steps = std::min(k.steps, 60);
    std::vector<float> dt1, dt3;
    const auto one = run(k.c, 1, steps, cuda_kernels(k.c.dim), &dt1), three = run(k.c, 3, steps, cuda_kernels(k.c.dim), &dt3);
    EXPECT_EQ(dt1, dt3);
    expect_same(one, three);
  }
  // Faces moved by the balancer hand particles over between GPU slabs.
  const Case c = small_dam_break();
  expect_same(run(c, 3, 12, cuda_kernels(c.dim)), run(c, 3, 12, cuda_kernels(c.dim), nullptr, 3));
}

TEST(CudaBackend, StagedHaloLinksGiveTheSameAnswerAndAreTaken) {
  // SPATE_CUDA_HALO_LINK=staged sends every halo of one process through pinned host memory, the
  // path that slabs on GPUs without peer access (or on other ranks) take; on one GPU every link is
  // otherwise a same-device copy. Bit for bit the same, and the bytes show which path was taken.
  if (no_gpu()) GTEST_SKIP() << why_no_gpu();
  const Case c = small_dam_break();
  const auto one = run(c, 1, 12, cuda_kernels(c.dim));
  const gpu::HaloTraffic before = gpu::halo_traffic();
  const auto peer = run(c, 3, 12, cuda_kernels(c.dim));
  const gpu::HaloTraffic between = gpu::halo_traffic();
  ::setenv("SPATE_CUDA_HALO_LINK", "staged", 1);
  const auto staged = run(c, 3, 12, cuda_kernels(c.dim));
  ::unsetenv("SPATE_CUDA_HALO_LINK");
  const gpu::HaloTraffic after = gpu::halo_traffic();
  expect_same(one, peer);
  expect_same(one, staged);
  EXPECT_GT(between.peer_bytes, before.peer_bytes);
  EXPECT_EQ(between.staged_bytes, before.staged_bytes);
  EXPECT_GT(after.staged_bytes, between.staged_bytes);
  EXPECT_EQ(after.peer_bytes, between.peer_bytes);
}

TEST(CudaBackend, ANanTimeStepIsZeroWhereverThatParticleSits) {
  // The CUB minimum over the particles' steps would keep or drop a NaN depending on where its
  // reduction tree meets it; particle_time_step gives 0 instead, as on the CPU.
  if (no_gpu()) GTEST_SKIP() << why_no_gpu();
  const Case c = small_dam_break();
  const PhysicsParams P = physics_params(c);
  ParticleStore p = generate_particles(c);
  auto kernels = gpu::make_cuda_kernels(0, c.dim);
  std::size_t first_fluid = 0;
  while (!P.is_fluid(p.material[first_fluid])) ++first_fluid;
  kernels->arrays().upload(p);
  const float healthy = kernels->min_time_step(p, P, TimeStepControl{});
  EXPECT_EQ(healthy, cpu::min_time_step(p, P, TimeStepControl{}));
  EXPECT_GT(healthy, 0.0f);
  for (std::size_t i : {first_fluid, p.owned() / 2, p.owned() - 1}) {
    if (!P.is_fluid(p.material[i])) continue;
    ParticleStore q = p;
    q.vel[0][i] = NAN;
    kernels->arrays().upload(q);
    EXPECT_EQ(kernels->min_time_step(q, P, TimeStepControl{}), 0.0f) << "NaN at " << i;
  }
}

}  // namespace spate

