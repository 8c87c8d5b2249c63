#pragma once
// The Levenberg–Marquardt optimiser of the output-error fit on one Problem
// (forward_model.hpp): the weighted residual, its Jacobian (exact, or
// through the port models' tangent), the LM loop and the exact J at an
// answer. The LM loop is one function, levenberg_marquardt (fitter.cpp).
// Internal to update/output_error/.
#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "update/output_error.hpp"
#include "update/output_error/common.hpp"
#include "update/output_error/forward_model.hpp"
#include "update/output_error/noise.hpp"

namespace piezo::update::oe {

struct LmOutcome {
  Eigen::VectorXd x;
  double cost = 0;  // ½‖r/σ‖²
  bool converged = false;
  int iterations = 0;
  std::string message;
  Eigen::VectorXd r;       // weighted residual at x
  Eigen::MatrixXd j, jtj;  // at the answer (the runs that need them, see finish)
};

// The optimiser on one Problem: the weighted residual, its Jacobian, LM and
// the exact J at an answer. The scan of the catalogue's effects runs one per
// thread, each on its own Problem (Problem's fork, in_parallel).
class Fitter {
 public:
  Fitter(Problem& prob, const OffsetWhitening& whiten, const double& sigma, const OeOptions& opt, double dof_fit)
      : prob(prob), whiten(whiten), sigma(sigma), opt(opt), dof_fit(dof_fit) {}
  // The same optimiser on another Problem (a fork for another thread): the
  // same whitening, noise (by reference) and options.
  Fitter on(Problem& other) const { return Fitter(other, whiten, sigma, opt, dof_fit); }
  // The fit's degrees of freedom (the whitening's nuisance columns changed).
  void set_dof(double dof) { dof_fit = dof; }

  // r/σ after the offsets' whitening; empty when x cannot be simulated.
  std::optional<Eigen::VectorXd> weighted(const Eigen::VectorXd& x);
  // Columns from `first` on (the others kept as they are in j). The
  // constants' columns through the port models' tangent near the last exact
  // Jacobian (Problem::set_tangent), unless `exact`.
  bool jacobian(const Eigen::VectorXd& x, const Eigen::VectorXd& r0, Eigen::MatrixXd& j, int first = 0,
                bool exact = false);
  // ½‖r/σ‖² at x on the port models' tangent anchored at `anchor`
  // (Problem::tangent_model), NaN away from it.
  double tangent_cost(const Eigen::VectorXd& anchor, const Eigen::VectorXd& x);
  // LM from x. A later start (`lead`: the optimum of the first) stops early
  // once it is inside the lead's optimum (ΔxᵀJᵀJΔx < 9 at no lower cost: it
  // would converge there, and no constant differs by 3 of its statistical
  // sigmas, so the honesty check's 3-sigma test (sigma.cpp) cannot fire) or once it
  // stalls far above it (its cost gap to the lead above max(50, 10·s²) and
  // shrinking by less than a tenth per iteration: a local optimum the data
  // reject, which the honesty check ignores anyway).
  // `j0`: the Jacobian at x when the caller has it (an effect scanned from the
  // optimum: the five's columns there are the optimum's), saving its models.
  // `freeze_material`: with j0, the four material columns stay j0's (an
  // effect scanned from the optimum moves the constants by a fraction of their
  // sigmas: their columns barely change, and each costs an FE port model);
  // β's and the effect's are recomputed (no new model). finish() computes the
  // exact J at the answer for the covariance.
  LmOutcome levenberg_marquardt(Eigen::VectorXd x, const LmOutcome* lead, const Eigen::MatrixXd* j0 = nullptr,
                                bool freeze_material = false);
  // J and JᵀJ at a run's answer (only the best one's are used), exact: the
  // covariances are read from it (through the tangent, an effect's sigma
  // came out up to a tenth off where it trades with epsT33).
  void finish(LmOutcome& o);

  Problem& prob;

 private:
  const OffsetWhitening& whiten;
  const double& sigma;  // the noise the residual is weighted by (re-weighed once at the answer)
  const OeOptions& opt;
  double dof_fit;
};

// The fit's answer as the stages after the optimiser read it (sigma.hpp,
// lack_of_fit.hpp, effect_scan.hpp).
struct FitAnswer {
  const std::vector<LmOutcome>& runs;          // every refined start's run, best first
  const LmOutcome& best;                       // runs.front(), re-weighed to the noise at it
  const std::optional<std::vector<cd>>& t;     // T at the answer (empty: it cannot be simulated)
  double dof = 1;                              // ν of the five-parameter fit
  double s2 = 1;                               // max(1, χ²/ν), the Birge factor
  double ch1 = 0, ch2 = 0;                     // white noise of each channel of the record, volts
};

}  // namespace piezo::update::oe
