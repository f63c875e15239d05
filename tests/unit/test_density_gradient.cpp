// The renormalised density gradient and Antuono's delta-SPH diffusion
// (solver/physics/density_gradient.hpp) on lattices of spacing dp: the gradient of a linear density
// is exact inside, at a free surface and in a corner (where the plain SPH gradient is not), the
// diffusion of a linear density is zero everywhere (where the Molteni-Colagrossi form is not), and a
// density bump is flattened.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <stdexcept>
#include <vector>

#include "lattice_params.hpp"
#include "physics/density_gradient.hpp"

namespace spate {
namespace {

const std::string kAntuono = "density:\n  diffusion: antuono\n";

template <int Dim>
struct LatticeBlock {
  PhysicsParams P;
  const FluidMaterial* M;
  std::vector<ParticleState<Dim>> all;
  // Sites k dp for -8 <= k <= top along every axis, with density rho(x).
  LatticeBlock(int top, const std::function<float(const Vec<Dim>&)>& rho)
      : P(lattice_params(Dim, kAntuono)), M(&P.materials.fluid[0]) {
    int k[3] = {-8, -8, -8};
    for (k[0] = -8; k[0] <= top; ++k[0])
      for (k[1] = -8; k[1] <= top; ++k[1])
        for (k[2] = (Dim == 3 ? -8 : 0); k[2] <= (Dim == 3 ? top : 0); ++k[2]) {
          ParticleState<Dim> s{};
          for (int a = 0; a < Dim; ++a) s.x[a] = k[a] * P.dp;
          s.rho = rho(s.x);
          s.material = 0;
          all.push_back(s);
        }
  }
  const ParticleState<Dim>& at(const Vec<Dim>& x) const {
    for (const auto& s : all)
      if (dot(s.x - x, s.x - x) < 1e-10f) return s;
    throw std::runtime_error("no such site");
  }
  Vec<Dim> gradient(const ParticleState<Dim>& i) const {
    DensityGradientSums<Dim> s;
    for (const auto& j : all) accumulate_density_gradient<WendlandC2, Dim>(P, *M, i, j, s);
    return renormalised_gradient<Dim>(s);
  }
  // The plain SPH gradient sum_j (rho_j - rho_i) grad_i W_ij V_j (no renormalisation).
  Vec<Dim> raw_gradient(const ParticleState<Dim>& i) const {
    DensityGradientSums<Dim> s;
    for (const auto& j : all) accumulate_density_gradient<WendlandC2, Dim>(P, *M, i, j, s);
    return s.raw;
  }
  float antuono(const ParticleState<Dim>& i) const {
    float d = 0.0f;
    const Vec<Dim> gi = gradient(i);
    for (const auto& j : all) d += antuono_diffusion_term<WendlandC2, Dim>(P, *M, i, gi, j, gradient(j));
    return d;
  }
  float molteni(const ParticleState<Dim>& i) const {
    float d = 0.0f;
    for (const auto& j : all) {
      const Vec<Dim> r = i.x - j.x;
      const float r2 = dot(r, r);
      if (r2 >= P.support2) continue;
      const float F = kernel_gradient_factor<WendlandC2>(P, r2);
      d += diffusion_flux(P, *M, 1.0f, j.rho - i.rho, r2, F, 1.0f / (r2 + P.eta2), M->mass / j.rho);
    }
    return d;
  }
};

// A density gradient of 0.5 rho0 per metre in x and -2 rho0 per metre in y (and 1 in z): within
// the support a change of about 1%, the size of an impact's dynamic density field.
template <int Dim>
float linear(const Vec<Dim>& x) {
  float rho = 1000.0f * (1.0f + 0.5f * x[0] - 2.0f * x[1]);
  if constexpr (Dim == 3) rho += 1000.0f * x[2];
  return rho;
}

TEST(DensityGradient, RenormalisedGradientOfALinearDensityIsExactInsideAtTheSurfaceAndInACorner) {
  LatticeBlock<2> L(0, linear<2>);  // free surfaces at x = 0 and y = 0: (0, 0) is a corner
  for (const Vec<2> x : {Vec<2>{-0.04f, -0.04f}, Vec<2>{-0.04f, 0.0f}, Vec<2>{0.0f, 0.0f}, Vec<2>{-0.01f, 0.0f}}) {
    const Vec<2> g = L.gradient(L.at(x));
    SCOPED_TRACE(testing::Message() << "at (" << x[0] << ", " << x[1] << ")");
    EXPECT_NEAR(g[0], 500.0f, 0.5f);
    EXPECT_NEAR(g[1], -2000.0f, 2.0f);
  }
  // The plain gradient is close inside (within the 4-8% the volumes m / rho_j of a 1000-1080 kg/m^3
  // density take from it) and wrong by far at the surface (half the support is missing).
  const Vec<2> raw_inside = L.raw_gradient(L.at(Vec<2>{-0.04f, -0.04f}));
  EXPECT_NEAR(raw_inside[1], -2000.0f, 200.0f);
  const Vec<2> raw_surface = L.raw_gradient(L.at(Vec<2>{-0.04f, 0.0f}));
  EXPECT_GT(raw_surface[1], -1200.0f);
}

TEST(DensityGradient, RenormalisedGradientIsExactIn3D) {
  LatticeBlock<3> L(0, linear<3>);
  // Inside, on an edge (two free surfaces) and in a corner (three).
  for (const Vec<3> x : {Vec<3>{-0.04f, -0.04f, -0.04f}, Vec<3>{0.0f, -0.03f, 0.0f}, Vec<3>{0.0f, 0.0f, 0.0f}}) {
    const Vec<3> g = L.gradient(L.at(x));
    EXPECT_NEAR(g[0], 500.0f, 0.5f);
    EXPECT_NEAR(g[1], -2000.0f, 2.0f);
    EXPECT_NEAR(g[2], 1000.0f, 1.0f);
  }
}

TEST(DensityGradient, ASparseNeighbourhoodTakesNoGradient) {
  LatticeBlock<2> L(0, linear<2>);
  // A lone particle with one neighbour: the matrix is singular.
  std::vector<ParticleState<2>> pair = {L.all[0], L.all[1]};
  DensityGradientSums<2> s;
  for (const auto& j : pair) accumulate_density_gradient<WendlandC2, 2>(L.P, *L.M, pair[0], j, s);
  const Vec<2> g = renormalised_gradient<2>(s);
  EXPECT_EQ(g[0], 0.0f);
  EXPECT_EQ(g[1], 0.0f);
}

TEST(DensityGradient, AntuonoDiffusionOfALinearDensityIsZeroEvenAtTheSurface) {
  LatticeBlock<2> L(0, linear<2>);
  for (const Vec<2> x : {Vec<2>{-0.04f, -0.04f}, Vec<2>{-0.04f, 0.0f}, Vec<2>{0.0f, 0.0f}}) {
    const ParticleState<2>& i = L.at(x);
    // The scale: what Molteni & Colagrossi's form (no gradient correction) gives at the surface.
    const float molteni_surface = std::fabs(L.molteni(L.at(Vec<2>{-0.04f, 0.0f})));
    EXPECT_GT(molteni_surface, 50.0f);  // kg/m^3/s: a linear density is diffused at a free surface
    EXPECT_LT(std::fabs(L.antuono(i)), 1e-3f * molteni_surface) << "at (" << x[0] << ", " << x[1] << ")";
  }
}

TEST(DensityGradient, AntuonoDiffusionFlattensABump) {
  // rho = rho0 (1 + 0.01 exp(-|x|^2 / (2 (2 dp)^2))): a maximum at the origin loses density, its
  // flanks gain it.
  LatticeBlock<2> L(8, [](const Vec<2>& x) { return 1000.0f * (1.0f + 0.01f * std::exp(-dot(x, x) / (2 * 0.02f * 0.02f))); });
  EXPECT_LT(L.antuono(L.at(Vec<2>{0.0f, 0.0f})), 0.0f);
  EXPECT_GT(L.antuono(L.at(Vec<2>{0.05f, 0.0f})), 0.0f);
}

}  // namespace
}  // namespace spate
