// Heat transfer (physics/heat_transfer.hpp): the conduction pair term, the wall temperature behind
// a face, the compensated temperature sum, the conduction time step, the case keys and their errors.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "case_errors.hpp"
#include "case/case.hpp"
#include "particles/particle_store.hpp"
#include "physics/fluid_interactions.hpp"
#include "physics/heat_transfer.hpp"
#include "physics/integrator.hpp"
#include "physics/timestep.hpp"
#include "sim/steering.hpp"

namespace spate {
namespace {

// Twice the harmonic mean: equal conductivities give 2k; one adiabatic (k = 0) side none at all.
TEST(HeatTransfer, PairConductivityIsTwiceTheHarmonicMean) {
  EXPECT_FLOAT_EQ(pair_conductivity(1.0f, 1.0f), 2.0f);
  EXPECT_FLOAT_EQ(pair_conductivity(10.0f, 1.0f), 40.0f / 11.0f);
  EXPECT_FLOAT_EQ(pair_conductivity(0.0f, 5.0f), 0.0f);
  EXPECT_FLOAT_EQ(pair_conductivity(0.0f, 0.0f), 0.0f);
}

// The pair exchanges heat, it does not make any: V_i x (i's term) = -V_j x (j's term), whatever the
// conductivities and volumes; and the hotter particle cools.
TEST(HeatTransfer, ConductionConservesHeatPairByPair) {
  PhysicsParams P;
  const float h = 0.013f, dp = 0.01f;
  P.h = h, P.inv_h = 1.0f / h, P.inv_h2 = P.inv_h * P.inv_h, P.eta2 = 0.01f * h * h;
  P.gradient_norm = WendlandC2::normalisation(2, h);
  P.heat.laplacian_scale = 1.1f;
  const Vec<2> xi{{0.0f, 0.0f}}, xj{{0.008f, 0.011f}};
  const float vi = dp * dp * 0.98f, vj = dp * dp * 1.03f, k = pair_conductivity(0.6f, 15.0f);
  const float ti = 350.0f, tj = 300.0f;
  auto term = [&](const Vec<2>& a, float ta, const Vec<2>& b, float tb, float v) {
    const PairKinematics<2> pk = radial_kinematics<WendlandC2, 2>(P, a, b);
    return conduction_term(P.heat, pk.r2, pk.F, pk.inv_r2_eta, ta, tb, k, v);
  };
  const float to_i = term(xi, ti, xj, tj, vj);
  const float to_j = term(xj, tj, xi, ti, vi);
  EXPECT_LT(to_i, 0.0f);
  EXPECT_GT(to_j, 0.0f);
  EXPECT_NEAR(vi * to_i, -vj * to_j, 1e-6 * std::fabs(vi * to_i));
  // The Laplacian's normalisation: the gradient's times laplacian_scale.
  const float r2 = 0.008f * 0.008f + 0.011f * 0.011f;
  const float expected = vj * k * (ti - tj) * 1.1f * WendlandC2::gradient_factor(std::sqrt(r2) / h, P.gradient_norm, P.inv_h2) *
                         r2 / (r2 + P.eta2);
  EXPECT_NEAR(to_i, expected, 1e-5 * std::fabs(expected));
  // Beyond the support (2h = 0.026): nothing, without a test of the distance (the kernel is 0 there).
  const Vec<2> far{{0.03f, 0.0f}};
  EXPECT_EQ(term(xi, ti, far, tj, vj), 0.0f);
}

// The fit recovers a linear temperature's gradient from scattered neighbours; the mirror value is
// limited to the neighbours' range; neighbours in one line give no gradient (the Shepard fallback).
TEST(HeatTransfer, MirrorTemperatureFromTheFittedGradient) {
  LinearFitSums<2> s;
  const float gx = 3.0f, gy = -2.0f;
  const float pts[][2] = {{0.1f, 0.4f}, {-0.7f, 0.9f}, {0.5f, 1.3f}, {1.1f, 0.6f}, {-0.2f, 1.7f}, {0.8f, 1.9f}};
  for (auto& p : pts) s.add(0.3f + 0.1f * p[0] * p[0], Vec<2>{{p[0], p[1]}}, 300.0f + gx * p[0] + gy * p[1]);
  const Vec<2> g = fitted_gradient<2>(s);
  EXPECT_NEAR(g[0], gx, 1e-3);
  EXPECT_NEAR(g[1], gy, 1e-3);
  // From the neighbour at (0.1, 0.4) to the point (0.1, 0.9): inside the range, exact.
  const Vec<2> up{{0.0f, 0.5f}}, right{{100.0f, 0.0f}}, left{{-100.0f, 0.0f}};
  EXPECT_NEAR(mirror_temperature<2>(s, 300.0f + gx * 0.1f + gy * 0.4f, g, up), 300.0f + gx * 0.1f + gy * 0.9f, 1e-3);
  // Far beyond the neighbours: held at their extremes.
  EXPECT_FLOAT_EQ(mirror_temperature<2>(s, 300.0f, g, right), s.highest);
  EXPECT_FLOAT_EQ(mirror_temperature<2>(s, 300.0f, g, left), s.lowest);
  LinearFitSums<2> line;
  for (int k = 0; k < 4; ++k) line.add(1.0f, Vec<2>{{0.5f * k, 1.0f}}, 300.0f + k);
  const Vec<2> none = fitted_gradient<2>(line);
  EXPECT_EQ(none[0], 0.0f);
  EXPECT_EQ(none[1], 0.0f);
}

// A wall particle behind a face lies on the straight line through the particle nearest its mirror
// point: behind a face at T_f, T_f - (T_near - T_f) depth / near_depth (2 T_f - T_near when the
// particle is its mirror image); behind a face passing q into the fluid, T_near + q (depth +
// near_depth) / k; adiabatic, T_near. A deep layer's line through the first row is exact for a
// linear profile.
TEST(HeatTransfer, FaceConditions) {
  const FaceCondition fixed{ThermalCondition::FaceTemperature, 310.0f}, flux{ThermalCondition::FaceFlux, 200.0f};
  EXPECT_FLOAT_EQ(face_wall_temperature(fixed, 305.0f, 0.01f, 1.0f, 0.01f), 315.0f);
  EXPECT_FLOAT_EQ(face_wall_temperature(flux, 300.0f, 0.01f, 0.5f, 0.01f), 308.0f);
  EXPECT_FLOAT_EQ(face_wall_temperature(FaceCondition{ThermalCondition::Adiabatic, 0.0f}, 301.5f, 0.01f, 0.5f, 0.01f), 301.5f);
  // T = 310 + 1000 s (s into the fluid): the row at s = 0.005 gives the layer at depth 0.015.
  EXPECT_NEAR(face_wall_temperature(fixed, 315.0f, 0.005f, 1.0f, 0.015f), 310.0f - 15.0f, 1e-3);
  // Flux into the fluid q = -k dT/ds = -2000 W/m2 for k = 2.
  EXPECT_NEAR(face_wall_temperature(FaceCondition{ThermalCondition::FaceFlux, -2000.0f}, 315.0f, 0.005f, 2.0f, 0.015f), 295.0f, 1e-3);
  // A tank particle in a corner belongs to the face of the lower axis; inside, to none.
  const float lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
  const float corner[3] = {-0.05f, 1.05f, 0}, inside[3] = {0.5f, 0.5f, 0}, top[3] = {0.5f, 1.15f, 0};
  EXPECT_EQ(thermal_face(lo, hi, corner, 2).index(), 0);
  EXPECT_EQ(thermal_face(lo, hi, inside, 2).axis, -1);
  const ThermalFace f = thermal_face(lo, hi, top, 2);
  EXPECT_EQ(f.index(), 3);
  EXPECT_FLOAT_EQ(f.depth, 0.15f);
  EXPECT_FLOAT_EQ(f.into_fluid, -1.0f);
}

// A million increments of 1e-6 K added to 300 K: a plain float sum never moves (each is below half
// the resolution at 300 K), the compensated one arrives at 301 K.
TEST(HeatTransfer, CompensatedSumKeepsIncrementsBelowTheResolution) {
  float plain = 300.0f, value = 300.0f, residual = 0.0f;
  for (int k = 0; k < 1000000; ++k) {
    plain += 1.0e-6f;
    compensated_add(value, residual, 1.0e-6f);
  }
  EXPECT_EQ(plain, 300.0f);
  EXPECT_NEAR(value, 301.0f, 1e-4);
}

const char* kSlab = R"(
name: slab
dimensions: 2
dp: 0.005
gravity: [0, 0]
heat: {initial_temperature: 300, gravity: [0, -9.81]}
fluid:
  thermal: {conductivity: 0.6, specific_heat: 4000, expansion: 2.0e-4}
time: {end: 1}
tank:
  size: [0.1, 0.05]
  open_top: false
  thermal:
    faces:
      x-: {temperature: 310}
      x+: {heat_flux: -50}
fluid_blocks:
  - {min: [0, 0], max: [0.1, 0.05]}
)";

using test::error_of;

TEST(HeatTransfer, CaseKeysBecomeTheHeatParams) {
  const Case c = parse_case(kSlab, "slab.yaml");
  const PhysicsParams P = physics_params(c);
  ASSERT_TRUE(P.heat.on);
  EXPECT_FLOAT_EQ(P.heat.material(0).conductivity, 0.6f);
  EXPECT_FLOAT_EQ(P.heat.material(0).reference_temperature, 300.0f);  // default: the initial temperature
  EXPECT_EQ(P.heat.face[0].kind, ThermalCondition::FaceTemperature);
  EXPECT_EQ(P.heat.face[1].kind, ThermalCondition::FaceFlux);
  EXPECT_FLOAT_EQ(P.heat.face[1].value, -50.0f);
  EXPECT_EQ(P.heat.face[2].kind, ThermalCondition::Adiabatic);  // a tank that does not conduct
  EXPECT_FLOAT_EQ(P.heat.gravity[1], -9.81f);
  EXPECT_EQ(optional_field_groups(P), kThermal);
  // The conduction limit: 0.1 rho c_p h^2 / k.
  const double limit = 0.1 * 1000.0 * 4000.0 * P.h * P.h / 0.6;
  EXPECT_NEAR(heat_time_step(P, TimeStepControl{}), limit, 1e-6 * limit);
  EXPECT_FALSE(physics_params(parse_case(kSlab, "slab.yaml", {"heat=null", "fluid.thermal=null", "tank.thermal=null"})).heat.on);
}

// Whether an error message names the key and says why.
bool names(const std::string& message, const std::string& key, const std::string& why) {
  const bool ok = message.find("key '" + key + "'") != std::string::npos && message.find(why) != std::string::npos;
  if (!ok) std::printf("message: %s\n", message.c_str());
  return ok;
}

// Bad input names the key and the reason.
TEST(HeatTransfer, BadInputIsRefused) {
  EXPECT_TRUE(names(error_of(kSlab, {"fluid.thermal.conductivity=-1"}), "fluid.thermal.conductivity", "must be >= 0"));
  EXPECT_TRUE(names(error_of(kSlab, {"fluid.thermal.specific_heat=0"}), "fluid.thermal.specific_heat", "must be > 0"));
  EXPECT_NE(error_of(kSlab, {"heat.initial_temperature=-3"}).find("below absolute zero"), std::string::npos);
  EXPECT_TRUE(names(error_of(kSlab, {"tank.thermal.faces.x-.temperature=-1"}), "tank.thermal.faces.x-.temperature", "is below absolute zero"));
  EXPECT_TRUE(names(error_of(kSlab, {"tank.thermal.faces.z-=adiabatic"}), "tank.thermal.faces.z-", "is not a face of this 2D tank"));
  EXPECT_NE(error_of(kSlab, {"tank.open_top=true", "tank.thermal.faces.y+={temperature: 300}"}).find("its top is open"), std::string::npos);
  EXPECT_NE(error_of(kSlab, {"tank.thermal.faces.x-=conducting"}).find("needs tank.thermal.conductivity > 0"), std::string::npos);
  EXPECT_NE(error_of(kSlab, {"tank.thermal.faces.x-={temperature: 300, heat_flux: 1}"}).find("expected adiabatic, conducting"), std::string::npos);
  // Buoyancy without gravity (neither the case's nor heat.gravity).
  EXPECT_TRUE(names(error_of(kSlab, {"heat.gravity=[0, 0]"}), "fluid.thermal.expansion", "buoyancy needs gravity"));
  // Thermal keys without heat transfer; heat transfer without a fluid's properties.
  EXPECT_TRUE(names(error_of(kSlab, {"heat=null"}), "fluid.thermal", "heat transfer is off"));
  EXPECT_TRUE(names(error_of(kSlab, {"fluid.thermal=null"}), "fluid.thermal", "is required with heat transfer"));
  EXPECT_TRUE(names(error_of(kSlab, {"solids=[{name: s, min: [0.01, 0], max: [0.02, 0.01], thermal: {conductivity: 5}}]"}),
                    "solids[0].thermal.specific_heat", "is required"));
  EXPECT_NE(error_of(kSlab, {"probes=[{name: q, type: heat_flux, face: x-, length: 0.05}]"})
                .find("needs both length and temperature_difference"),
            std::string::npos);
}

// A fluid's viscosity table: linear between its points, the end values beyond them; the case's
// table reaches the physics constants, the viscous time step takes its largest value, and bad
// tables are rejected with the key and the reason.
TEST(HeatTransfer, ViscosityTable) {
  ViscosityTable t;
  t.points = 3;
  const float T[] = {290, 300, 310}, mu[] = {2e-3f, 1e-3f, 0.5e-3f};
  for (int k = 0; k < 3; ++k) t.temperature[k] = T[k], t.viscosity[k] = mu[k];
  EXPECT_FLOAT_EQ(table_viscosity(t, 295.0f), 1.5e-3f);
  EXPECT_FLOAT_EQ(table_viscosity(t, 307.5f), 0.625e-3f);
  EXPECT_FLOAT_EQ(table_viscosity(t, 300.0f), 1e-3f);
  EXPECT_FLOAT_EQ(table_viscosity(t, 250.0f), 2e-3f);
  EXPECT_FLOAT_EQ(table_viscosity(t, 400.0f), 0.5e-3f);
  const std::string table = "fluid.thermal.viscosity=[[290, 2.0e-3], [300, 1.0e-3], [310, 0.5e-3]]";
  const Case c = parse_case(kSlab, "slab.yaml", {table});
  const PhysicsParams P = physics_params(c);
  EXPECT_TRUE(P.heat.viscosity_varies);
  EXPECT_FLOAT_EQ(P.heat.viscosity(0, 7.0f, 305.0f), 0.75e-3f);
  EXPECT_FLOAT_EQ(P.heat.viscosity(1, 7.0f, 305.0f), 7.0f);  // the tank: no table
  EXPECT_FLOAT_EQ(P.materials.fluid[0].viscosity, 1e-3f);    // the stand-in: at the starting temperature
  EXPECT_FLOAT_EQ(viscous_time_step(P, TimeStepControl{}), TimeStepControl{}.viscous_factor * P.h * P.h * 1000.0f / 2e-3f);
  EXPECT_FALSE(physics_params(parse_case(kSlab, "slab.yaml")).heat.viscosity_varies);
  EXPECT_TRUE(names(error_of(kSlab, {"fluid.thermal.viscosity=[[300, 1.0e-3], [290, 2.0e-3]]"}), "fluid.thermal.viscosity", "must ascend"));
  EXPECT_TRUE(names(error_of(kSlab, {"fluid.thermal.viscosity=[[300, 1.0e-3]]"}), "fluid.thermal.viscosity", "at least 2 rows"));
  EXPECT_TRUE(names(error_of(kSlab, {"fluid.thermal.viscosity=[[-1, 1.0e-3], [290, 2.0e-3]]"}), "fluid.thermal.viscosity", "below absolute zero"));
  EXPECT_TRUE(names(error_of(kSlab, {"fluid.thermal.viscosity=[[280, -1.0e-3], [290, 2.0e-3]]"}), "fluid.thermal.viscosity", "must be >= 0"));
  EXPECT_TRUE(names(error_of(kSlab, {"fluid.thermal.viscosity=[[280, 1, 2], [290, 2.0e-3]]"}), "fluid.thermal.viscosity", "expected a table"));
  EXPECT_TRUE(names(error_of(kSlab, {table, "fluid.viscosity=1e-3"}), "fluid.viscosity", "give one or the other"));
  // Steering a viscosity that follows its table is rejected.
  EXPECT_NE(validate(SteeringChange{0, 0.0, "viscosity", {2e-3}}, 2, nullptr, &c).value_or("").find("follows its viscosity table"),
            std::string::npos);
  EXPECT_FALSE(validate(SteeringChange{0, 0.0, "viscosity", {2e-3}}, 2, nullptr, nullptr).has_value());
}

// Steering a face (docs/live.md): face_temperature and face_heat_flux name a wall the tank has, in a
// case with heat transfer; the change sets the face's kind and value (an adiabatic face may be heated).
TEST(HeatTransfer, SteeringAFace) {
  const Case c = parse_case(kSlab, "slab.yaml");
  auto change = [](const std::string& name, double face, double value) { return SteeringChange{0, 0.0, name, {face, value}}; };
  EXPECT_FALSE(validate(change("face_temperature", 1, 300), 2, nullptr, &c).has_value());
  EXPECT_FALSE(validate(change("face_heat_flux", 2, -50), 2, nullptr, &c).has_value());
  EXPECT_NE(validate(change("face_temperature", 4, 300), 2, nullptr, &c).value_or("").find("not a face of this 2D tank"), std::string::npos);
  EXPECT_NE(validate(change("face_temperature", 1.5, 300), 2, nullptr, &c).value_or("").find("whole number from 0 to 5"), std::string::npos);
  EXPECT_NE(validate(change("face_temperature", 1, -2), 2, nullptr, &c).value_or("").find("outside"), std::string::npos);
  const Case open = parse_case(kSlab, "slab.yaml", {"tank.open_top=true"});
  EXPECT_NE(validate(change("face_heat_flux", 3, 10), 2, nullptr, &open).value_or("").find("its top is open"), std::string::npos);
  const Case cold = parse_case(kSlab, "slab.yaml", {"heat=null", "fluid.thermal=null", "tank.thermal=null"});
  EXPECT_NE(validate(change("face_temperature", 1, 300), 2, nullptr, &cold).value_or("").find("no heat transfer"), std::string::npos);
  // Without the case (a log read before the run), only the ranges.
  EXPECT_FALSE(validate(change("face_temperature", 4, 300), 2).has_value());
  PhysicsParams P = physics_params(c);
  SteeringTarget t{&P};
  apply(change("face_heat_flux", 2, -50), t);
  EXPECT_EQ(P.heat.face[2].kind, ThermalCondition::FaceFlux);
  EXPECT_EQ(P.heat.face[2].value, -50.0f);
  apply(change("face_temperature", 1, 300), t);
  EXPECT_EQ(P.heat.face[1].kind, ThermalCondition::FaceTemperature);
  EXPECT_EQ(P.heat.face[1].value, 300.0f);
}

// A run with heat transfer carries the temperature (its residual, rates, the mirror conductivity and
// the gradient) in its stores; a run without it
// pays nothing: the same fields, the same bytes per particle.
TEST(HeatTransfer, OnlyRunsWithHeatCarryTheTemperature) {
  const std::size_t without = ParticleStore(2).bytes_per_particle();
  {
    const OptionalFields thermal(FieldGroups{kThermal});
    ParticleStore p(2);
    p.resize(3);
    EXPECT_EQ(p.temperature.size(), 3u);
    EXPECT_TRUE(p.colour_gradient[0].empty());  // the other optional group stays out
    EXPECT_EQ(p.bytes_per_particle(), without + (5 + 2) * sizeof(float));  // 5 scalars, the 2D gradient
  }
  ParticleStore q(2);
  q.resize(3);
  EXPECT_TRUE(q.temperature.empty());
  EXPECT_EQ(q.bytes_per_particle(), without);
}

}  // namespace
}  // namespace spate
