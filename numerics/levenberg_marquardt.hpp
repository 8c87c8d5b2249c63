#pragma once
// The one least-squares engine of piezobench (issue 32): Levenberg–Marquardt
// with Marquardt's diagonal scaling, minimising ½‖r(x)‖². Every fit — the
// BVD branch (dsp/bvd_fit), the fixture calibration (dsp/fixture_calibration),
// the seed's LM update (update/least_squares), the port model
// (update/port_fit), the gap fit (update/gap_fit) and the output-error fit
// (update/output_error) — writes only its residual and Jacobian; the loop,
// the damping, the step control, the stopping tests and the covariance live
// here, as Ceres keeps them for COLMAP's and Theia's callers.
//
// Why not Ceres itself: the output-error fit screens each trial step on a
// cheap surrogate (the port models' tangent) before it pays for an FE model,
// extends accepted steps along curved valleys, retries a failed iteration on
// the exact Jacobian, and stops a later start early once it joins the first
// start's optimum. Ceres' trust-region loop offers no veto of a trial before
// its evaluation nor a choice of Jacobian per iteration; emulating them
// through failed evaluations would cost the FE models the screen saves.
// So the engine is ours, in this one file, with those as optional hooks.
//
// Settings are per problem, as Ceres' Solver::Options are: the damping
// factors and tolerances each caller had before the engine existed are kept
// in its settings (their study figures were measured with them).

#include <Eigen/Dense>
#include <cmath>
#include <functional>
#include <limits>
#include <optional>
#include <string>

namespace piezo::numerics {

struct LmSettings {
  int max_iterations = 100;
  int max_tries = 14;           // trial steps per iteration (μ grows after each rejected one)
  double mu0 = 1e-3;            // initial damping
  double mu_down = 3.0;         // μ ← max(μ / mu_down, mu_min) after an accepted step
  double mu_min = 1e-12;
  double mu_up = 4.0;           // μ ← μ · mu_up after a rejected trial
  double diag_floor = 1e-300;   // A = JᵀJ + μ·diag(max((JᵀJ)_pp, diag_floor))
  double max_step = std::numeric_limits<double>::infinity();  // trust region: largest |Δx_p| of a step
  // … per coordinate instead, when not empty (its size x's): a step is scaled
  // down, its direction kept, until every |Δx_p| ≤ max_step_each[p] (∞: no
  // bound on that coordinate). For coordinates of different kinds, e.g. the
  // logs of material constants beside an effect counted in typical sizes.
  Eigen::VectorXd max_step_each;
  bool accept_equal = false;    // accept a trial that leaves the cost unchanged (≤ instead of <)
  // Convergence after an accepted step: its largest |Δx_p| below step_tolerance,
  // or the cost's drop below cost_tolerance, or drop/cost below
  // relative_cost_tolerance (each off at 0).
  double step_tolerance = 0;
  double cost_tolerance = 0;
  double relative_cost_tolerance = 0;
  // A rejected trial whose step is already below step_tolerance ends the run
  // as converged (no smaller step can lower the cost any more).
  bool tiny_rejected_step_converges = true;
  // An iteration in which no trial lowers the cost:
  enum class Stall {
    converged,        // a minimum to rounding
    gradient_cosine,  // converged only if the residual is orthogonal to J's columns (cosine < stall_cosine)
    failed,           // not converged
  };
  Stall on_stall = Stall::gradient_cosine;
  double stall_cosine = 1e-4;
  // Before the stall verdict, the iteration runs again on the exact Jacobian
  // (LmJacobianCall::exact) with the screen off; the damping is restored if
  // only the screen refused.
  bool retry_exact = false;
  // After an accepted step, go on along it, doubling (within max_step), while
  // the cost keeps falling and μ < extend_below_mu: one residual per try
  // instead of a Jacobian per step along a curved valley.
  int extend_steps = 0;
  double extend_below_mu = 1e-2;
  // Recompute J at the answer when the last accepted step moved x after it
  // (LmRun::j is then the Jacobian at LmRun::x).
  bool jacobian_at_answer = true;
};

struct LmJacobianCall {
  int iteration = 0;   // 1-based
  bool exact = false;  // a retry (LmSettings::retry_exact) or the answer's J: no surrogate
};

// Where the run is after an iteration (for LmProblem::after_iteration and
// LmProblem::converged_after_step).
struct LmState {
  const Eigen::VectorXd& x;
  const Eigen::VectorXd& step;  // the last accepted step (before any extension)
  double cost;                  // ½‖r‖² at x
  double last_drop;             // the cost's decrease by the last accepted step
  int iteration;
};

struct LmVerdict {
  bool stop = false;
  bool converged = false;
  std::string message;
};

struct LmProblem {
  // r(x); nullopt where the model cannot be evaluated (the trial is rejected).
  std::function<std::optional<Eigen::VectorXd>(const Eigen::VectorXd& x)> residual;
  // J at x (r = r(x) given); false where it cannot be computed (the run ends).
  // j keeps its previous contents between calls: a caller may update columns.
  std::function<bool(const Eigen::VectorXd& x, const Eigen::VectorXd& r, Eigen::MatrixXd& j,
                     const LmJacobianCall& call)>
      jacobian;
  // Optional: bounds, applied to every trial (e.g. a clamp to a box).
  std::function<void(Eigen::VectorXd& x)> project;
  // Optional: the cost a surrogate predicts for `trial` from `anchor` (NaN: no
  // prediction). A trial predicted at or above the current cost is rejected
  // without evaluating the residual.
  std::function<double(const Eigen::VectorXd& anchor, const Eigen::VectorXd& trial)> screen;
  // Optional: an extra convergence test after each accepted step.
  std::function<bool(const LmState&)> converged_after_step;
  // Optional: after each iteration with an accepted step, stop the run.
  std::function<LmVerdict(const LmState&)> after_iteration;
};

struct LmRun {
  enum class Stop {
    converged,           // a tolerance met, or a stall judged a minimum
    bad_start,           // r(x0) cannot be evaluated
    jacobian_failed,     // J could not be computed
    stalled,             // no trial lowers the cost and the stall is not a minimum
    iteration_limit,
    stopped_by_caller,   // after_iteration stopped it without convergence
  };
  Eigen::VectorXd x;
  Eigen::VectorXd r;   // r(x)
  Eigen::MatrixXd j;   // the last Jacobian (at x when LmSettings::jacobian_at_answer)
  double cost = std::numeric_limits<double>::infinity();  // ½‖r‖²
  bool converged = false;
  Stop stop = Stop::iteration_limit;
  int iterations = 0;        // begun (1-based count)
  int residuals = 0;         // evaluations of r
  int jacobians = 0;         // evaluations of J
  double stall_cosine = 0;   // the gradient cosine of a stall (Stop::stalled, or a stall judged converged)
  std::string message;       // from after_iteration, when it stopped the run
};

LmRun levenberg_marquardt(const LmProblem& problem, Eigen::VectorXd x0, const LmSettings& settings);

// Forward-difference Jacobian columns [first, x.size()) of `residual` at x
// with steps h[c]; a failed side is replaced by the backward difference.
// False when neither side can be evaluated.
bool forward_difference_jacobian(
    const std::function<std::optional<Eigen::VectorXd>(const Eigen::VectorXd&)>& residual,
    const Eigen::VectorXd& x, const Eigen::VectorXd& r, const Eigen::VectorXd& h, Eigen::MatrixXd& j);

// (JᵀJ)⁺ — the covariance of x for whitened residuals (unit noise), by a
// complete orthogonal decomposition (rank-deficient directions get 0, not ∞).
Eigen::MatrixXd lm_covariance(const Eigen::MatrixXd& j);

}  // namespace piezo::numerics
