// The shared least-squares engine (numerics/levenberg_marquardt) against problems
// whose answers are known in closed form: a linear model (normal equations),
// Rosenbrock's valley, a bound, a region the model cannot evaluate, and the
// hooks the callers use (screen, exact retry, caller's stop).
#include "numerics/levenberg_marquardt.hpp"

#include <gtest/gtest.h>

#include <initializer_list>
#include <limits>
#include <random>
#include <stdexcept>

using namespace piezo::numerics;

namespace {

// A VectorXd of these values (not = Vector2d(…): GCC 12 with AVX warns
// falsely of an out-of-bounds packet load, GCC bug 106247).
Eigen::VectorXd vec(std::initializer_list<double> v) {
  Eigen::VectorXd x(static_cast<Eigen::Index>(v.size()));
  Eigen::Index i = 0;
  for (double e : v) x[i++] = e;
  return x;
}

LmProblem linear_problem(const Eigen::MatrixXd& a, const Eigen::VectorXd& y) {
  LmProblem pb;
  pb.residual = [a, y](const Eigen::VectorXd& x) -> std::optional<Eigen::VectorXd> { return a * x - y; };
  pb.jacobian = [a](const Eigen::VectorXd&, const Eigen::VectorXd&, Eigen::MatrixXd& j,
                    const LmJacobianCall&) {
    j = a;
    return true;
  };
  return pb;
}

LmProblem rosenbrock() {
  LmProblem pb;
  pb.residual = [](const Eigen::VectorXd& x) -> std::optional<Eigen::VectorXd> {
    Eigen::VectorXd r(2);
    r << 10.0 * (x[1] - x[0] * x[0]), 1.0 - x[0];
    return r;
  };
  pb.jacobian = [](const Eigen::VectorXd& x, const Eigen::VectorXd&, Eigen::MatrixXd& j,
                   const LmJacobianCall&) {
    j.resize(2, 2);
    j << -20.0 * x[0], 10.0, -1.0, 0.0;
    return true;
  };
  return pb;
}

}  // namespace

TEST(LevenbergMarquardt, LinearModelGivesTheNormalEquationsAnswerAndCovariance) {
  std::mt19937 rng(32);
  std::normal_distribution<double> n01;
  Eigen::MatrixXd a(40, 3);
  Eigen::VectorXd y(40);
  for (int i = 0; i < 40; ++i) {
    const double t = i / 40.0;
    a.row(i) << 1.0, t, t * t;
    y[i] = 0.5 - 2.0 * t + 3.0 * t * t + 0.01 * n01(rng);
  }
  LmSettings s;
  s.step_tolerance = 1e-12;
  const auto run = levenberg_marquardt(linear_problem(a, y), Eigen::VectorXd::Zero(3), s);
  ASSERT_TRUE(run.converged);
  const Eigen::VectorXd x_ls = a.colPivHouseholderQr().solve(y);
  EXPECT_LT((run.x - x_ls).cwiseAbs().maxCoeff(), 1e-9);
  const Eigen::MatrixXd cov = (a.transpose() * a).inverse();
  EXPECT_LT((lm_covariance(run.j) - cov).cwiseAbs().maxCoeff(), 1e-9 * cov.cwiseAbs().maxCoeff());
  EXPECT_NEAR(run.cost, 0.5 * (a * x_ls - y).squaredNorm(), 1e-12);
}

TEST(LevenbergMarquardt, RosenbrockValleyReachesTheMinimum) {
  for (const int extend : {0, 4}) {
    LmSettings s;
    s.step_tolerance = 1e-12;
    s.extend_steps = extend;
    Eigen::VectorXd x0(2);
    x0 << -1.2, 1.0;
    const auto run = levenberg_marquardt(rosenbrock(), x0, s);
    ASSERT_TRUE(run.converged) << "extend " << extend;
    EXPECT_NEAR(run.x[0], 1.0, 1e-8);
    EXPECT_NEAR(run.x[1], 1.0, 1e-8);
    EXPECT_LT(run.cost, 1e-20);
  }
}

TEST(LevenbergMarquardt, ProjectionHoldsABound) {
  // min ½(x − 2)² with x ≤ 1: the answer is the bound, and no trial beyond it is evaluated.
  LmProblem pb;
  double largest = -1e300;
  pb.residual = [&](const Eigen::VectorXd& x) -> std::optional<Eigen::VectorXd> {
    largest = std::max(largest, x[0]);
    return Eigen::VectorXd::Constant(1, x[0] - 2.0);
  };
  pb.jacobian = [](const Eigen::VectorXd&, const Eigen::VectorXd&, Eigen::MatrixXd& j,
                   const LmJacobianCall&) {
    j = Eigen::MatrixXd::Ones(1, 1);
    return true;
  };
  pb.project = [](Eigen::VectorXd& x) { x[0] = std::min(x[0], 1.0); };
  LmSettings s;
  s.accept_equal = true;
  s.relative_cost_tolerance = 1e-12;
  s.on_stall = LmSettings::Stall::converged;
  const auto run = levenberg_marquardt(pb, Eigen::VectorXd::Zero(1), s);
  EXPECT_TRUE(run.converged);
  EXPECT_DOUBLE_EQ(run.x[0], 1.0);
  EXPECT_LE(largest, 1.0);
}

TEST(LevenbergMarquardt, TrialsTheModelCannotEvaluateAreRejected) {
  // The minimum (x = 1) lies where the model fails (x > 0.5): the run ends
  // below 0.5, stalled on a gradient that is not zero, never past the edge.
  LmProblem pb;
  pb.residual = [](const Eigen::VectorXd& x) -> std::optional<Eigen::VectorXd> {
    if (x[0] > 0.5) return std::nullopt;
    return Eigen::VectorXd::Constant(1, x[0] - 1.0);
  };
  pb.jacobian = [](const Eigen::VectorXd&, const Eigen::VectorXd&, Eigen::MatrixXd& j,
                   const LmJacobianCall&) {
    j = Eigen::MatrixXd::Ones(1, 1);
    return true;
  };
  LmSettings s;
  s.max_tries = 40;
  s.max_iterations = 2000;
  const auto run = levenberg_marquardt(pb, Eigen::VectorXd::Zero(1), s);
  EXPECT_LE(run.x[0], 0.5);
  EXPECT_GT(run.x[0], 0.49);
  EXPECT_FALSE(run.converged);
  EXPECT_EQ(run.stop, LmRun::Stop::stalled);
  EXPECT_GT(run.stall_cosine, 0.9);  // the residual points straight along J: no minimum

  Eigen::VectorXd bad(1);
  bad << 0.7;
  EXPECT_EQ(levenberg_marquardt(pb, bad, s).stop, LmRun::Stop::bad_start);
}

TEST(LevenbergMarquardt, StallVerdictFollowsTheSettings) {
  // A Jacobian of the wrong sign: no trial ever lowers the cost.
  LmProblem pb = linear_problem(Eigen::MatrixXd::Identity(2, 2), Eigen::VectorXd::Ones(2));
  pb.jacobian = [](const Eigen::VectorXd&, const Eigen::VectorXd&, Eigen::MatrixXd& j,
                   const LmJacobianCall&) {
    j = -Eigen::MatrixXd::Identity(2, 2);
    return true;
  };
  LmSettings s;
  s.on_stall = LmSettings::Stall::failed;
  EXPECT_EQ(levenberg_marquardt(pb, Eigen::VectorXd::Zero(2), s).stop, LmRun::Stop::stalled);
  s.on_stall = LmSettings::Stall::gradient_cosine;
  EXPECT_EQ(levenberg_marquardt(pb, Eigen::VectorXd::Zero(2), s).stop, LmRun::Stop::stalled);
  s.on_stall = LmSettings::Stall::converged;
  const auto run = levenberg_marquardt(pb, Eigen::VectorXd::Zero(2), s);
  EXPECT_TRUE(run.converged);
  EXPECT_EQ(run.x, Eigen::VectorXd::Zero(2));  // never moved
}

TEST(LevenbergMarquardt, ExactRetryRescuesAWrongSurrogateJacobian) {
  LmProblem pb = linear_problem(Eigen::MatrixXd::Identity(2, 2), Eigen::VectorXd::Ones(2));
  int exact_calls = 0;
  pb.jacobian = [&](const Eigen::VectorXd&, const Eigen::VectorXd&, Eigen::MatrixXd& j,
                    const LmJacobianCall& call) {
    if (call.exact) ++exact_calls;
    // The surrogate is wrong on the first iteration only.
    j = (call.exact || call.iteration > 1 ? 1.0 : -1.0) * Eigen::MatrixXd::Identity(2, 2);
    return true;
  };
  LmSettings s;
  s.step_tolerance = 1e-12;
  s.on_stall = LmSettings::Stall::failed;
  EXPECT_EQ(levenberg_marquardt(pb, Eigen::VectorXd::Zero(2), s).stop, LmRun::Stop::stalled);
  s.retry_exact = true;
  const auto run = levenberg_marquardt(pb, Eigen::VectorXd::Zero(2), s);
  EXPECT_TRUE(run.converged);
  EXPECT_LT((run.x - Eigen::VectorXd::Ones(2)).norm(), 1e-9);
  EXPECT_GT(exact_calls, 0);
}

TEST(LevenbergMarquardt, ScreenSavesEvaluationsWithoutMovingTheAnswer) {
  // A surrogate that knows the cost exactly refuses every trial that would
  // raise it: the same answer with no more evaluations of the residual.
  LmSettings s;
  s.step_tolerance = 1e-12;
  Eigen::VectorXd x0(2);
  x0 << -1.2, 1.0;
  const auto plain = levenberg_marquardt(rosenbrock(), x0, s);
  LmProblem pb = rosenbrock();
  pb.screen = [r = pb.residual](const Eigen::VectorXd&, const Eigen::VectorXd& x) {
    return 0.5 * r(x)->squaredNorm();
  };
  const auto screened = levenberg_marquardt(pb, x0, s);
  ASSERT_TRUE(screened.converged);
  EXPECT_LT((screened.x - plain.x).norm(), 1e-8);
  EXPECT_LE(screened.residuals, plain.residuals);
}

TEST(LevenbergMarquardt, CallerStopsTheRun) {
  LmProblem pb = rosenbrock();
  pb.after_iteration = [](const LmState& st) {
    return LmVerdict{st.iteration >= 2, false, "enough"};
  };
  Eigen::VectorXd x0(2);
  x0 << -1.2, 1.0;
  const auto run = levenberg_marquardt(pb, x0, LmSettings{});
  EXPECT_EQ(run.stop, LmRun::Stop::stopped_by_caller);
  EXPECT_EQ(run.iterations, 2);
  EXPECT_EQ(run.message, "enough");
}

TEST(LevenbergMarquardt, ForwardDifferencesMatchTheAnalyticJacobian) {
  const auto pb = rosenbrock();
  Eigen::VectorXd x(2);
  x << 0.3, -0.4;
  Eigen::MatrixXd ja, jf;
  pb.jacobian(x, *pb.residual(x), ja, {});
  ASSERT_TRUE(forward_difference_jacobian(pb.residual, x, *pb.residual(x), Eigen::VectorXd::Constant(2, 1e-7), jf));
  EXPECT_LT((ja - jf).cwiseAbs().maxCoeff(), 1e-5);
}

// LmSettings::max_step_each: a linear problem whose answer is 0.1 in its first
// coordinate and 8 in its second. With one cap of 0.3 on both, every step is
// scaled to 0.3 in the second and the run takes ⌈8/0.3⌉ iterations (the old
// output-error effect scan); with the second uncapped and the first at 0.3
// (not binding on the first, whose whole way is 0.1) one step reaches the
// normal equations' answer. A cap binds per coordinate: with the first
// capped at 0.01 the first step moves it by exactly 0.01, the direction kept.
TEST(LevenbergMarquardt, PerCoordinateTrustRegionBindsOnlyItsCoordinate) {
  Eigen::MatrixXd a(3, 2);
  a << 1.0, 0.0, 0.0, 1.0, 1.0, 1.0;
  Eigen::VectorXd y(3);
  y << 0.1, 8.0, 8.1;  // x = (0.1, 8) fits exactly
  LmSettings s;
  s.step_tolerance = 1e-12;
  s.mu0 = 1e-12;  // a Gauss-Newton step, so the caps alone limit it
  s.max_step = 0.3;
  const auto one_cap = levenberg_marquardt(linear_problem(a, y), Eigen::VectorXd::Zero(2), s);
  ASSERT_TRUE(one_cap.converged);
  EXPECT_GE(one_cap.iterations, 27);
  s.max_step_each = vec({0.3, std::numeric_limits<double>::infinity()});
  const auto each = levenberg_marquardt(linear_problem(a, y), Eigen::VectorXd::Zero(2), s);
  ASSERT_TRUE(each.converged);
  EXPECT_LE(each.iterations, 3);  // the step to the answer, then the ones that find nothing lower
  EXPECT_NEAR(each.x[0], 0.1, 1e-12);
  EXPECT_NEAR(each.x[1], 8.0, 1e-12);
  // The first coordinate's cap binds: the step is scaled as a whole.
  s.max_step_each = vec({0.01, std::numeric_limits<double>::infinity()});
  s.max_iterations = 1;
  const auto first = levenberg_marquardt(linear_problem(a, y), Eigen::VectorXd::Zero(2), s);
  EXPECT_NEAR(first.x[0], 0.01, 1e-12);
  EXPECT_NEAR(first.x[1], 0.8, 1e-9);
  // One cap per coordinate, each positive.
  s.max_step_each = vec({0.3, 0.3, 0.3});
  EXPECT_THROW(levenberg_marquardt(linear_problem(a, y), Eigen::VectorXd::Zero(2), s), std::invalid_argument);
  s.max_step_each = vec({0.3, 0.0});
  EXPECT_THROW(levenberg_marquardt(linear_problem(a, y), Eigen::VectorXd::Zero(2), s), std::invalid_argument);
}
