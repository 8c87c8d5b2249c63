#pragma once
// Second, independent updater for comparison with CMCM: Levenberg–Marquardt
// on the same measured quantities, with FE sensitivities.
//   unknowns  x = ln(p/p0) for p = (YE11, nu12, |d31|, εT33) (dimensionless, sign-safe)
//   residuals relative errors of the resonances, the anti-resonances and the
//             FE capacitance at f_L (divided by the relative σ's when given)
//   Jacobian  frequencies by Hellmann–Feynman, dλ/dx = φᵀ (∂K/∂x) φ with the
//             condensed short/open-circuit stiffness (update/condensed_stiffness.hpp);
//             the capacitance by a forward difference of the static solve.
// No coordinates, phases or mode-shape iteration are shared with CMCM.
#include <string>
#include <vector>

#include "model/modal.hpp"
#include "update/cmcm.hpp"
#include "update/features.hpp"
#include "update/parametrization.hpp"

namespace piezo::update {

struct LmOptions {
  int max_iterations = 60;
  double step_tolerance = 1e-10;  // converged when max |Δx| < this (relative parameter change)
  double lambda0 = 1e-3;          // initial Marquardt damping (relative to diag JᵀJ)
  model::ModalOptions modal = CmcmOptions{}.modal;
};

struct LmResult {
  UpdateStatus status = UpdateStatus::bad_input;
  std::string message;
  TubeParams updated;
  int iterations = 0, evaluations = 0;
  double cost = 0;                // ½‖r‖² at the answer
  std::vector<double> residuals;  // resonances, anti-resonances, capacitance (relative)
  std::vector<double> model_resonances_hz, model_antiresonances_hz;
  double seconds = 0;
  bool ok() const { return status == UpdateStatus::converged; }
};

LmResult update_lm(const model::TubeModel& tube, model::ModalSolver& solver,
                   const MaterialClass& cls, const TubeParams& original,
                   const MeasuredFeatures& features, const LmOptions& options = {});

}  // namespace piezo::update
