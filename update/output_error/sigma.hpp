#pragma once
// The output-error fit's uncertainty and honesty: the covariance of its
// coordinates at the answer, cov = s²·(JᵀJ)⁻¹ (s² = max(1, χ²/ν), the Birge
// factor), plus the measurement chain's type-B part (R1, a parallel
// capacitance, channel gain and skew, each propagated through
// dθ/db = −(JᵀJ)⁻¹Jᵀ ∂r/∂b); then each parameter's value, sigma and status —
// "not identifiable" for a singular fit, a lack of fit, a relative sigma
// beyond its limit, or another start's equally good optimum more than 3
// sigma away. Internal to update/output_error/.
#include <Eigen/Core>

#include "update/output_error.hpp"
#include "update/output_error/fitter.hpp"
#include "update/output_error/forward_model.hpp"
#include "update/output_error/noise.hpp"

namespace piezo::update::oe {

struct Covariance {
  Eigen::MatrixXd cov;      // of the fit's coordinates: statistical and type B (NaN when singular)
  Eigen::VectorXd sx_stat;  // the coordinates' statistical sigmas (Birge-widened)
  Eigen::VectorXd sx;       // … with the type-B part
};

// The covariance at the answer; out.covariance_rel gets its statistical part
// relative to the answer (OeResult::covariance_rel). `sigma`: the noise the
// runs are weighted by; out.updated must hold the answer.
Covariance covariance(const FitAnswer& answer, Problem& prob, const OffsetWhitening& whiten,
                      double sigma, const TubeParams& nominal, const OeOptions& opt, OeResult& out);

// out.correlation, corr_nu12_d31, qm and qm_sigma (complex constants) and
// out.parameters with their honesty checks. After judge_lack_of_fit
// (lack_of_fit.hpp): a lack of fit makes every constant not identifiable.
void identify(const FitAnswer& answer, const Covariance& c, const TubeParams& nominal,
              const OeOptions& opt, OeResult& out);

}  // namespace piezo::update::oe
