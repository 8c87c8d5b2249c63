// Element and quadrature: Gauss exactness, Q2 basis, and physical invariants of
// the axisymmetric element (mass = ρ·volume, rigid translation strain-free,
// exact uniform-strain response).
#include <gtest/gtest.h>

#include <cmath>

#include "model/element.hpp"

using namespace piezo::model;

namespace {
std::array<Node, 9> rect(double r0, double r1, double z0, double z1) {
  std::array<Node, 9> x;
  for (int b = 0; b < 3; ++b)
    for (int a = 0; a < 3; ++a) x[3 * b + a] = {r0 + 0.5 * a * (r1 - r0), z0 + 0.5 * b * (z1 - z0)};
  return x;
}
}  // namespace

TEST(Quadrature, GaussLegendreIsExactToDegree2nMinus1) {
  for (int n = 1; n <= 4; ++n) {
    auto g = gauss_legendre(n);
    for (int p = 0; p <= 2 * n - 1; ++p) {
      double s = 0;
      for (int i = 0; i < n; ++i) s += g.w[i] * std::pow(g.x[i], p);
      const double exact = (p % 2) ? 0.0 : 2.0 / (p + 1);
      EXPECT_NEAR(s, exact, 1e-14) << "n=" << n << " p=" << p;
    }
  }
  EXPECT_THROW(gauss_legendre(5), std::invalid_argument);
}

TEST(Element, LagrangeBasisInterpolatesAndSumsToOne) {
  const double nodes[3] = {-1, 0, 1};
  for (int a = 0; a < 3; ++a) {
    auto l = lagrange2(nodes[a]);
    for (int b = 0; b < 3; ++b) EXPECT_DOUBLE_EQ(l[b], a == b ? 1.0 : 0.0);
  }
  for (double xi : {-0.7, 0.1, 0.55}) {
    auto l = lagrange2(xi);
    auto d = lagrange2_deriv(xi);
    EXPECT_NEAR(l[0] + l[1] + l[2], 1.0, 1e-15);
    EXPECT_NEAR(d[0] + d[1] + d[2], 0.0, 1e-15);
  }
}

TEST(Element, MassIsVolumeOfTheRing) {
  ElementSplit es;
  const double r0 = 0.008, r1 = 0.0095, z0 = -0.001, z1 = 0.0005;
  element_split(rect(r0, r1, z0, z1), 3, es);
  // Σ_ab M(u_r a, u_r b) = ∫ dV = π(r1² − r0²)(z1 − z0), exact for 3 Gauss points.
  double s = 0;
  for (int a = 0; a < 9; ++a)
    for (int b = 0; b < 9; ++b) s += es.m(2 * a, 2 * b);
  const double vol = M_PI * (r1 * r1 - r0 * r0) * (z1 - z0);
  EXPECT_NEAR(s / vol, 1.0, 1e-13);
}

TEST(Element, RigidAxialTranslationIsStrainFree) {
  ElementSplit es;
  element_split(rect(0.008, 0.0095, 0.0, 0.002), 3, es);
  Eigen::Matrix<double, 27, 1> u = Eigen::Matrix<double, 27, 1>::Zero();
  for (int a = 0; a < 9; ++a) u[2 * a + 1] = 1.0;  // u_z = 1
  for (int p = 0; p < kNumMaterialParams; ++p)
    EXPECT_LT((es.k[p] * u).norm(), 1e-6 * es.k[p].norm() + 1e-300) << param_name(MaterialParam(p));
  // A uniform potential produces no field either.
  Eigen::Matrix<double, 27, 1> phi = Eigen::Matrix<double, 27, 1>::Zero();
  phi.tail(9).setOnes();
  for (int p = 0; p < kNumMaterialParams; ++p) EXPECT_LT((es.k[p] * phi).norm(), 1e-9 * (es.k[p].norm() + 1));
}

TEST(Element, UniformRadialExpansionEnergyMatchesClosedForm) {
  // u_r = ε0·r gives S_rr = S_θθ = ε0, S_zz = γ = 0 exactly (quadratic basis reproduces
  // it); energy uᵀ K_c11 u = ∫ (S1² + S2²)... with only S2 = S_θθ in the (1,1)+(2,2)
  // pattern of cE11: uᵀK_c11u = ε0²·V, uᵀK_c33u = ε0²·V, uᵀK_c13u = 2ε0²·V.
  ElementSplit es;
  const double r0 = 0.008, r1 = 0.0095, z0 = 0, z1 = 0.002, eps = 1e-4;
  auto x = rect(r0, r1, z0, z1);
  element_split(x, 3, es);
  Eigen::Matrix<double, 27, 1> u = Eigen::Matrix<double, 27, 1>::Zero();
  for (int a = 0; a < 9; ++a) u[2 * a] = eps * x[a].r;
  const double vol = M_PI * (r1 * r1 - r0 * r0) * (z1 - z0);
  auto energy = [&](MaterialParam p) { return u.dot(es.k[static_cast<int>(p)] * u) / (eps * eps * vol); };
  EXPECT_NEAR(energy(MaterialParam::c11), 1.0, 1e-12);  // S2² (S1 = 0)
  EXPECT_NEAR(energy(MaterialParam::c12), 0.0, 1e-12);  // 2 S1 S2
  EXPECT_NEAR(energy(MaterialParam::c13), 2.0, 1e-12);  // 2 S2 S3
  EXPECT_NEAR(energy(MaterialParam::c33), 1.0, 1e-12);  // S3²
  EXPECT_NEAR(energy(MaterialParam::c44), 0.0, 1e-12);
}

TEST(Element, RadialFieldEnergyAndSeedSignOfKphiphi) {
  // φ = E0·(r − r0): E_r = −E0 uniform, so −φᵀK_eps33φ = E0²·V and K_eps11 sees nothing.
  ElementSplit es;
  const double r0 = 0.008, r1 = 0.0095, z0 = 0, z1 = 0.002, e0 = 1e3;
  auto x = rect(r0, r1, z0, z1);
  element_split(x, 3, es);
  Eigen::Matrix<double, 27, 1> phi = Eigen::Matrix<double, 27, 1>::Zero();
  for (int a = 0; a < 9; ++a) phi[18 + a] = e0 * (x[a].r - r0);
  const double vol = M_PI * (r1 * r1 - r0 * r0) * (z1 - z0);
  EXPECT_NEAR(-phi.dot(es.k[9] * phi) / (e0 * e0 * vol), 1.0, 1e-12);  // seed eq. 76 sign
  EXPECT_NEAR(phi.dot(es.k[8] * phi) / (e0 * e0 * vol), 0.0, 1e-12);
  // Split matrices are symmetric.
  for (int p = 0; p < kNumMaterialParams; ++p)
    EXPECT_LT((es.k[p] - es.k[p].transpose()).norm(), 1e-12 * (es.k[p].norm() + 1e-300));
}
