#pragma once
// The two Gauss–Newton loops that do not go through the Levenberg–Marquardt
// engine (levenberg_marquardt.hpp), as two small drivers: the caller writes
// its residual, Jacobian and step rule; the iteration, the step halving and
// the stopping tests live here (issue 42 item 6).
//
//  - penalised_gauss_newton: min over z of ‖r(z)‖² + zᵀ P z (P symmetric
//    positive definite, e.g. a covariance's inverse) by Gauss–Newton steps
//    (JᵀJ + P) δ = −(Jᵀr + P z), each halved until the cost drops. The
//    held-out prediction's penalised steps (update/output_error/prediction.cpp).
//  - gauss_newton: undamped steps J δ = −r by the caller's solver (a
//    truncated SVD, say) until the largest |δ_i| falls below a tolerance.
//    The mode-shape CMCM's refinement (update/mode_shape_cmcm.cpp, App. D).
//
// Neither draws its own Jacobian: the callers have analytic ones or a
// surrogate (the port models' tangent).

#include <Eigen/Dense>
#include <functional>
#include <optional>

namespace piezo::numerics {

struct PenalisedGnProblem {
  // r(z); nullopt where it cannot be evaluated (a trial step is then refused).
  std::function<std::optional<Eigen::VectorXd>(const Eigen::VectorXd& z)> residual;
  // J at z (r(z) = rz given); nullopt stops the iteration at the current z.
  std::function<std::optional<Eigen::MatrixXd>(const Eigen::VectorXd& z, const Eigen::VectorXd& rz)> jacobian;
};

struct PenalisedGnSettings {
  int max_iterations = 4;
  int max_halvings = 4;   // trial steps per iteration: δ, δ/2, δ/4, …
  double min_drop = 0.0;  // an accepted step dropping the cost by less stops the iteration
};

struct PenalisedGnResult {
  Eigen::VectorXd z;   // the last accepted point (z0 if none)
  Eigen::VectorXd r;   // r(z)
  double cost = 0.0;   // ‖r‖² + zᵀPz
  int iterations = 0;  // Jacobians evaluated
  int accepted = 0;    // steps taken
};

// Starts at z0 with r0 = r(z0) and cost0 = ‖r0‖² + z0ᵀPz0 as the caller has
// them (no evaluation is repeated).
PenalisedGnResult penalised_gauss_newton(const PenalisedGnProblem& problem, const Eigen::MatrixXd& penalty,
                                         const Eigen::VectorXd& z0, const Eigen::VectorXd& r0, double cost0,
                                         const PenalisedGnSettings& settings = {});

struct GaussNewtonProblem {
  // r and J at the current point (the caller holds the point).
  std::function<void(Eigen::VectorXd& r, Eigen::MatrixXd& jacobian)> linearise;
  // δ solving J δ ≈ −r in the caller's sense (least squares, truncated SVD).
  std::function<Eigen::VectorXd(const Eigen::MatrixXd& jacobian, const Eigen::VectorXd& minus_r)> solve;
  // Moves the caller's point by δ.
  std::function<void(const Eigen::VectorXd& step)> apply;
};

// Returns the iterations taken (≤ max_iterations; the one whose step fell
// below step_tolerance counts).
int gauss_newton(const GaussNewtonProblem& problem, int max_iterations, double step_tolerance);

}  // namespace piezo::numerics
