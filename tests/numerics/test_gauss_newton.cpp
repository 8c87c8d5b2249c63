// The two Gauss–Newton drivers (numerics/gauss_newton) against answers known
// in closed form: a penalised linear problem (one full step is the ridge
// solution (AᵀA + P)⁻¹Aᵀb), a penalised nonlinear one (the penalty's
// optimality condition Jᵀr + Pz = 0 at the answer), a residual that cannot
// be evaluated (no step taken), and the undamped driver on a nonlinear
// system with a root known exactly.
#include "numerics/gauss_newton.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace piezo::numerics;

namespace {

PenalisedGnProblem linear(const Eigen::MatrixXd& a, const Eigen::VectorXd& b, int* jacobians = nullptr) {
  PenalisedGnProblem pb;
  pb.residual = [a, b](const Eigen::VectorXd& z) -> std::optional<Eigen::VectorXd> { return a * z - b; };
  pb.jacobian = [a, jacobians](const Eigen::VectorXd&, const Eigen::VectorXd&) -> std::optional<Eigen::MatrixXd> {
    if (jacobians) ++*jacobians;
    return a;
  };
  return pb;
}

}  // namespace

TEST(PenalisedGaussNewton, OneStepIsTheRidgeSolutionOfALinearProblem) {
  std::mt19937 rng(3);
  std::normal_distribution<double> n01;
  Eigen::MatrixXd a(30, 4);
  Eigen::VectorXd b(30);
  for (int i = 0; i < 30; ++i) {
    b[i] = n01(rng);
    for (int j = 0; j < 4; ++j) a(i, j) = n01(rng);
  }
  const Eigen::MatrixXd p = Eigen::Vector4d(0.5, 2.0, 10.0, 0.1).asDiagonal();
  const Eigen::VectorXd exact = (a.transpose() * a + p).ldlt().solve(a.transpose() * b);
  const Eigen::VectorXd z0 = Eigen::VectorXd::Zero(4), r0 = -b;
  int jacobians = 0;
  const auto out = penalised_gauss_newton(linear(a, b, &jacobians), p, z0, r0, r0.squaredNorm(),
                                          {.max_iterations = 4, .max_halvings = 4, .min_drop = 1e-9});
  EXPECT_LT((out.z - exact).norm(), 1e-12 * exact.norm());
  // The second step is round-off: refused, or taken with a drop below min_drop; either stops the loop.
  EXPECT_GE(out.accepted, 1);
  EXPECT_EQ(out.iterations, 2);
  EXPECT_EQ(jacobians, 2);
  EXPECT_NEAR(out.cost, (a * exact - b).squaredNorm() + exact.dot(p * exact), 1e-10);
}

TEST(PenalisedGaussNewton, NonlinearAnswerMeetsItsOptimalityCondition) {
  // r(z) = (exp(z0) − 2, z0·z1 − 1, z1 − 0.5), P = 0.1·I.
  PenalisedGnProblem pb;
  pb.residual = [](const Eigen::VectorXd& z) -> std::optional<Eigen::VectorXd> {
    return Eigen::Vector3d(std::exp(z[0]) - 2.0, z[0] * z[1] - 1.0, z[1] - 0.5);
  };
  pb.jacobian = [](const Eigen::VectorXd& z, const Eigen::VectorXd&) -> std::optional<Eigen::MatrixXd> {
    Eigen::MatrixXd j(3, 2);
    j << std::exp(z[0]), 0.0, z[1], z[0], 0.0, 1.0;
    return j;
  };
  const Eigen::MatrixXd p = 0.1 * Eigen::MatrixXd::Identity(2, 2);
  const Eigen::VectorXd z0 = Eigen::Vector2d(0.2, 0.2);
  const Eigen::VectorXd r0 = *pb.residual(z0);
  const auto out = penalised_gauss_newton(pb, p, z0, r0, r0.squaredNorm() + z0.dot(p * z0),
                                          {.max_iterations = 50, .max_halvings = 8, .min_drop = 1e-15});
  const Eigen::VectorXd grad = pb.jacobian(out.z, out.r)->transpose() * out.r + p * out.z;
  EXPECT_LT(grad.norm(), 1e-6);
  EXPECT_LT(out.cost, r0.squaredNorm() + z0.dot(p * z0));
}

TEST(PenalisedGaussNewton, AResidualThatCannotBeEvaluatedTakesNoStep) {
  PenalisedGnProblem pb = linear(Eigen::MatrixXd::Identity(2, 2), Eigen::Vector2d(1.0, 1.0));
  pb.residual = [](const Eigen::VectorXd&) -> std::optional<Eigen::VectorXd> { return std::nullopt; };
  const Eigen::VectorXd z0 = Eigen::VectorXd::Zero(2), r0 = Eigen::Vector2d(-1.0, -1.0);
  const auto out = penalised_gauss_newton(pb, Eigen::MatrixXd::Identity(2, 2), z0, r0, 2.0);
  EXPECT_EQ(out.accepted, 0);
  EXPECT_EQ(out.z, z0);
  EXPECT_EQ(out.cost, 2.0);
}

TEST(GaussNewton, UndampedStepsReachAKnownRoot) {
  // r(x) = (x0² + x1² − 5, x0 − x1 + 1): root (1, 2) from (1.3, 1.6).
  Eigen::Vector2d x(1.3, 1.6);
  GaussNewtonProblem pb;
  pb.linearise = [&](Eigen::VectorXd& r, Eigen::MatrixXd& j) {
    r.resize(2);  // (not = Vector2d(…): GCC 12 with AVX warns falsely, bug 106247)
    r << x[0] * x[0] + x[1] * x[1] - 5.0, x[0] - x[1] + 1.0;
    j.resize(2, 2);
    j << 2 * x[0], 2 * x[1], 1.0, -1.0;
  };
  pb.solve = [](const Eigen::MatrixXd& j, const Eigen::VectorXd& minus_r) -> Eigen::VectorXd {
    return j.colPivHouseholderQr().solve(minus_r);
  };
  pb.apply = [&](const Eigen::VectorXd& s) { x += s; };
  const int it = gauss_newton(pb, 50, 1e-14);
  EXPECT_LT(it, 10);  // quadratic convergence: a handful of steps
  EXPECT_NEAR(x[0], 1.0, 1e-13);
  EXPECT_NEAR(x[1], 2.0, 1e-13);
  Eigen::Vector2d y(1.3, 1.6);
  x = y;
  EXPECT_EQ(gauss_newton(pb, 2, 1e-14), 2);  // the cap holds
}
