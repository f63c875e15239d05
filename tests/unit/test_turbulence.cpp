// SPS turbulence (solver/physics/turbulence.hpp) on lattices of spacing dp: the velocity gradient
// of a linear field is exact inside the fluid, a simple shear gets the Smagorinsky stress (nu_t =
// (C_s dp)^2 |S|, the isotropic part -(2/3) C_I dp^2 |S|^2), a rigid rotation none, and the stress
// divergence is the analytic one for a linear stress and zero for a uniform stress, also next to a
// wall whose particles carry the fluid's stress.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <vector>

#include "lattice_params.hpp"
#include "physics/turbulence.hpp"

namespace spate {
namespace {

const std::string kSps = "turbulence:\n  model: sps\n";

struct Lattice2D {
  PhysicsParams P = lattice_params(2, kSps);
  std::vector<ParticleState<2>> all;
  // Sites (k + 1/2) dp for -8 <= k < 8 along both axes, velocity v(x); rows below y = y_wall are
  // tank wall particles.
  Lattice2D(const std::function<Vec<2>(const Vec<2>&)>& v, float y_wall = -1.0f) {
    for (int a = -8; a < 8; ++a)
      for (int b = -8; b < 8; ++b) {
        ParticleState<2> s{};
        s.x[0] = (a + 0.5f) * P.dp;
        s.x[1] = (b + 0.5f) * P.dp;
        s.v = v(s.x);
        s.rho = 1000.0f;
        s.material = s.x[1] < y_wall ? P.materials.tank() : 0;
        all.push_back(s);
      }
  }
  const ParticleState<2>& centre() const { return all[8 * 16 + 8]; }  // (dp/2, dp/2)
  VelocityGradient<2> gradient(const ParticleState<2>& i) const {
    VelocityGradient<2> g;
    for (const auto& j : all) accumulate_velocity_gradient<WendlandC2, 2>(P, i, j, P.materials.fluid[0].mass / j.rho, g);
    return g;
  }
};

TEST(Turbulence, SimpleShearTakesTheSmagorinskyStress) {
  const float gamma = 3.0f;  // v_x = gamma y
  const Lattice2D L([&](const Vec<2>& x) { return Vec<2>{gamma * x[1], 0.0f}; });
  const VelocityGradient<2> g = L.gradient(L.centre());
  EXPECT_NEAR(g.g[1][0], gamma, 1e-3f * gamma);  // d v_x / d y
  EXPECT_NEAR(g.g[0][0], 0.0f, 1e-4f);
  EXPECT_NEAR(g.g[0][1], 0.0f, 1e-4f);
  EXPECT_NEAR(g.g[1][1], 0.0f, 1e-4f);
  float nu_t = 0.0f;
  const SpsStress<2> T = sps_stress<2>(L.P, g, 1000.0f, nu_t);
  // |S| = gamma for a simple shear; tau_xy = 2 nu_t S_xy = nu_t gamma.
  const float smag = 0.12f * L.P.dp, expected_nu = smag * smag * gamma;
  EXPECT_NEAR(nu_t, expected_nu, 2e-3f * expected_nu);
  EXPECT_NEAR(T.at(0, 1) * 1000.0f, expected_nu * gamma, 2e-3f * expected_nu * gamma);
  EXPECT_FLOAT_EQ(T.at(0, 1), T.at(1, 0));
  const float iso = -(2.0f / 3.0f) * 0.0066f * L.P.dp * L.P.dp * gamma * gamma;
  EXPECT_NEAR(T.at(0, 0) * 1000.0f, iso, 2e-3f * std::fabs(iso));
  EXPECT_NEAR(T.at(1, 1) * 1000.0f, iso, 2e-3f * std::fabs(iso));
}

TEST(Turbulence, ARigidRotationHasNoStress) {
  const float omega = 2.0f;
  const Lattice2D L([&](const Vec<2>& x) { return Vec<2>{-omega * x[1], omega * x[0]}; });
  float nu_t = 1.0f;
  const SpsStress<2> T = sps_stress<2>(L.P, L.gradient(L.centre()), 1000.0f, nu_t);
  EXPECT_NEAR(nu_t, 0.0f, 1e-3f * 0.0144f * L.P.dp * L.P.dp * omega);
  for (int a = 0; a < 2; ++a)
    for (int b = 0; b < 2; ++b) EXPECT_NEAR(T.at(a, b), 0.0f, 1e-12f);
}

TEST(Turbulence, ThreeDimensionalStrainIsSymmetricAndTracesTheIsotropicPart) {
  // v = A x with a symmetric, trace-free A: S = A, |S|^2 = 2 A:A.
  const PhysicsParams P = lattice_params(3, kSps);
  VelocityGradient<3> g;
  const float A[3][3] = {{1.0f, 0.5f, -0.2f}, {0.5f, -2.0f, 0.3f}, {-0.2f, 0.3f, 1.0f}};
  float AA = 0.0f;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) g.g[a][b] = A[b][a], AA += A[a][b] * A[a][b];
  float nu_t = 0.0f;
  const SpsStress<3> T = sps_stress<3>(P, g, 1000.0f, nu_t);
  const float smag2 = 0.12f * P.dp * 0.12f * P.dp;
  EXPECT_NEAR(nu_t, smag2 * std::sqrt(2.0f * AA), 1e-5f * nu_t);
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) {
      EXPECT_FLOAT_EQ(T.at(a, b), T.at(b, a));
      const float iso = a == b ? -(2.0f / 3.0f) * 0.0066f * P.dp * P.dp * 2.0f * AA : 0.0f;
      EXPECT_NEAR(T.at(a, b) * 1000.0f, 2.0f * nu_t * A[a][b] + iso, 1e-4f * std::fabs(2.0f * nu_t * A[a][b] + iso) + 1e-15f);
    }
}

// The divergence sum_j m_j (T_i + T_j) . grad_i W_ij of a stress field T(x) (with wall particles
// carrying i's stress), at particle i.
Vec<2> divergence(const Lattice2D& L, const ParticleState<2>& i, const std::function<SpsStress<2>(const Vec<2>&)>& T) {
  Vec<2> acc = zero_vec<2>();
  const float m = L.P.materials.fluid[0].mass;
  const SpsStress<2> Ti = T(i.x);
  for (const auto& j : L.all) acc += sps_pair_acceleration<WendlandC2, 2>(L.P, i.x, Ti, j.x, L.P.is_fluid(j.material) ? T(j.x) : Ti, m);
  return acc;
}

TEST(Turbulence, TheStressDivergenceIsTheAnalyticOne) {
  const Lattice2D L([](const Vec<2>&) { return zero_vec<2>(); });
  // tau_xy = c y, tau_xx = b x (kinematic): a = (b + c, 0) on a uniform density.
  const float b = 0.3f, c = 0.7f;
  const auto T = [&](const Vec<2>& x) {
    SpsStress<2> s;
    s.diagonal[0] = b * x[0] / 1000.0f;
    s.shear[0] = c * x[1] / 1000.0f;
    return s;
  };
  const Vec<2> a = divergence(L, L.centre(), T);
  EXPECT_NEAR(a[0], b + c, 2e-3f * (b + c));
  EXPECT_NEAR(a[1], 0.0f, 1e-3f * (b + c));
}

TEST(Turbulence, AUniformStressPushesNothingNextToAWall) {
  // Rows below y = 0 are wall particles; the first fluid row (y = dp/2) has a truncated fluid support.
  const Lattice2D L([](const Vec<2>&) { return zero_vec<2>(); }, 0.0f);
  const auto T = [](const Vec<2>&) {
    SpsStress<2> s;
    s.diagonal = Vec<2>{2e-4f, -1e-4f};
    s.shear[0] = 3e-4f;
    return s;
  };
  const Vec<2> a = divergence(L, L.centre(), T);
  // The scale of one neighbour's term: m T |grad W| ~ 1e-4 / dp.
  EXPECT_NEAR(a[0], 0.0f, 1e-6f / L.P.dp);
  EXPECT_NEAR(a[1], 0.0f, 1e-6f / L.P.dp);
  // Without the wall's stress (walls taking none), the same particle would be pushed.
  Vec<2> one_sided = zero_vec<2>();
  const float m = L.P.materials.fluid[0].mass;
  for (const auto& j : L.all)
    if (L.P.is_fluid(j.material)) one_sided += sps_pair_acceleration<WendlandC2, 2>(L.P, L.centre().x, T({}), j.x, T({}), m);
  EXPECT_GT(std::fabs(one_sided[1]), 1e-2f / L.P.dp);
}

TEST(Turbulence, TheCaseKeysSetTheModel) {
  const PhysicsParams off = lattice_params(2);
  EXPECT_FALSE(off.turbulence.on);
  EXPECT_EQ(optional_field_groups(off) & kTurbulence, 0);
  const PhysicsParams P = lattice_params(2, "turbulence:\n  model: sps\n  smagorinsky: 0.2\n  isotropic: 0\n", 0.02);
  EXPECT_TRUE(P.turbulence.on);
  EXPECT_EQ(optional_field_groups(P), kTurbulence);
  EXPECT_FLOAT_EQ(P.turbulence.smagorinsky2, 0.2f * 0.02f * 0.2f * 0.02f);
  EXPECT_FLOAT_EQ(P.turbulence.isotropic, 0.0f);
}

}  // namespace
}  // namespace spate
