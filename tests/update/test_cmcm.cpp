// update/cmcm: the classic CMCM equations (seed eqs 172-193) and the TSVD
// solve, on a small spring-mass chain where the exact answer is known.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include "update/cmcm.hpp"

namespace piezo::update {
namespace {

// Fixed-free chain of n masses: spring e joins node e−1 and e (node −1 = ground).
std::vector<Eigen::MatrixXd> chain_springs(int n, const std::vector<double>& k) {
  std::vector<Eigen::MatrixXd> ke;
  for (int e = 0; e < n; ++e) {
    Eigen::MatrixXd m = Eigen::MatrixXd::Zero(n, n);
    m(e, e) += k[e];
    if (e > 0) {
      m(e - 1, e - 1) += k[e];
      m(e - 1, e) -= k[e];
      m(e, e - 1) -= k[e];
    }
    ke.push_back(m);
  }
  return ke;
}

struct Eig {
  Eigen::VectorXd lambda;
  Eigen::MatrixXd phi;
};
Eig eig(const Eigen::MatrixXd& k, const Eigen::MatrixXd& m) {
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(k, m);
  return {es.eigenvalues(), es.eigenvectors()};
}

TEST(Tsvd, MinimumNormSolutionOfARankDeficientSystem) {
  Eigen::MatrixXd g(2, 2);
  g << 1, 1, 2, 2;
  Eigen::VectorXd f(2);
  f << 1, 2;
  const auto s = solve_tsvd(g, f);
  EXPECT_EQ(s.rank, 1);
  EXPECT_NEAR(s.x[0], 0.5, 1e-14);
  EXPECT_NEAR(s.x[1], 0.5, 1e-14);
  EXPECT_THROW(solve_tsvd(g, Eigen::VectorXd(3)), std::invalid_argument);
}

// Stiffness-only update with measured shapes: eq. 181 holds exactly for the
// true α, so G γ = f recovers it to round-off (tolerance 1e-9: cond(G) ~ 1e2).
TEST(CmcmClassic, RecoversStiffnessCorrectionsOfAChain) {
  const int n = 6;
  const std::vector<double> k0{4e6, 3e6, 3e6, 2e6, 2e6, 1e6};
  const std::vector<double> alpha{0.10, -0.05, 0.20, 0.0, -0.15, 0.08};
  const auto kn = chain_springs(n, k0);
  Eigen::MatrixXd k = Eigen::MatrixXd::Zero(n, n), ks = k;
  for (int e = 0; e < n; ++e) {
    k += kn[e];
    ks += (1 + alpha[e]) * kn[e];
  }
  const Eigen::MatrixXd m = Eigen::VectorXd::LinSpaced(n, 1.0, 2.0).asDiagonal();
  const auto a = eig(k, m), b = eig(ks, m);
  // Only the 4 lowest "measured" modes, arbitrarily scaled (CMCM needs no scaling).
  Eigen::MatrixXd phi_star = b.phi.leftCols(4);
  phi_star.col(1) *= -3.7;
  phi_star.col(3) *= 0.2;
  const auto eq = cmcm_equations(k, kn, m, {}, a.phi, a.lambda, phi_star, b.lambda.head(4));
  EXPECT_GE(eq.g.rows(), n);
  const auto s = solve_tsvd(eq.g, eq.f);
  ASSERT_EQ(s.rank, n);
  for (int e = 0; e < n; ++e) EXPECT_NEAR(s.x[e], alpha[e], 1e-9) << "element " << e;
}

// Simultaneous stiffness and mass correction (eq. 188, γ = [α; β]).
TEST(CmcmClassic, RecoversStiffnessAndMassCorrections) {
  const int n = 6;
  const std::vector<double> k0{4e6, 3e6, 3e6, 2e6, 2e6, 1e6};
  const auto kn = chain_springs(n, k0);
  // Two stiffness groups and two mass groups.
  std::vector<Eigen::MatrixXd> kg(2, Eigen::MatrixXd::Zero(n, n)),
      mg(2, Eigen::MatrixXd::Zero(n, n));
  for (int e = 0; e < n; ++e) kg[e < 3 ? 0 : 1] += kn[e];
  for (int i = 0; i < n; ++i) mg[i < 2 ? 0 : 1](i, i) = 1.0 + 0.1 * i;
  const Eigen::MatrixXd k = kg[0] + kg[1], m = mg[0] + mg[1];
  // Only the first mass group is updated: updating all stiffness and all mass
  // groups would leave (α, β) = t·(1, 1, 1, 1) in the null space of G.
  const Eigen::MatrixXd ks = 1.12 * kg[0] + 0.93 * kg[1], ms = 0.95 * mg[0] + mg[1];
  const auto a = eig(k, m), b = eig(ks, ms);
  const auto eq =
      cmcm_equations(k, kg, m, {mg[0]}, a.phi, a.lambda, b.phi.leftCols(3), b.lambda.head(3));
  const auto s = solve_tsvd(eq.g, eq.f);
  ASSERT_EQ(s.rank, 3);
  EXPECT_NEAR(s.x[0], 0.12, 1e-9);
  EXPECT_NEAR(s.x[1], -0.07, 1e-9);
  EXPECT_NEAR(s.x[2], -0.05, 1e-9);
}

// The test can fail: with the wrong model (α = 0 on one element that did change)
// the least-squares residual is not zero and the recovered α are off.
TEST(CmcmClassic, WrongParametrisationLeavesAResidual) {
  const int n = 6;
  const std::vector<double> k0{4e6, 3e6, 3e6, 2e6, 2e6, 1e6};
  auto kn = chain_springs(n, k0);
  Eigen::MatrixXd k = Eigen::MatrixXd::Zero(n, n), ks = k;
  for (int e = 0; e < n; ++e) {
    k += kn[e];
    ks += (e == 5 ? 1.3 : 1.0) * kn[e];
  }
  kn.pop_back();  // element 5 not among the updated ones
  const Eigen::MatrixXd m = Eigen::MatrixXd::Identity(n, n);
  const auto a = eig(k, m), b = eig(ks, m);
  const auto eq = cmcm_equations(k, kn, m, {}, a.phi, a.lambda, b.phi, b.lambda);
  const auto s = solve_tsvd(eq.g, eq.f);
  EXPECT_GT((eq.g * s.x - eq.f).norm(), 1e-3);
}

}  // namespace
}  // namespace piezo::update
