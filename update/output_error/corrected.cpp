// The output-error fit with the diagnosed effect, as a result of its own (corrected.hpp).
#include "update/output_error/corrected.hpp"

#include <cmath>
#include <cstdio>

#include "model/material.hpp"

namespace piezo::update {

std::optional<OeResult> corrected_result(const OeResult& r, const std::string& effect,
                                         double identifiable_rel_sigma) {
  const OeEffect* e = nullptr;
  for (const auto& c : r.effects)
    if (c.name == effect) e = &c;
  if (!e || !std::isfinite(e->value) || e->alias || r.parameters.size() < 5) return std::nullopt;
  OeResult c = r;
  c.effects.clear();
  c.updated = e->material;
  c.damping = {0.0, e->beta_s};
  c.eta = e->eta;
  c.damping_model = e->damping_model;
  c.effect_set = e->effect_set;
  c.chi2_per_dof = e->chi2_per_dof;
  c.band_log10_p = e->band_log10_p;
  c.lack_of_fit = !e->explains;
  c.regions.clear();
  const bool cov_ok = e->covariance_rel.rows() >= 5 && e->covariance_rel.cols() >= 5 &&
                      e->covariance_rel.topLeftCorner(5, 5).allFinite();
  c.covariance_rel = cov_ok ? Eigen::MatrixXd(e->covariance_rel.topLeftCorner(5, 5))
                            : Eigen::MatrixXd::Constant(5, 5, NAN);
  const bool complex_loss = e->damping_model == OeDamping::complex_constants;
  const double values[5] = {e->material.y_e11, e->material.nu12, e->material.d31,
                            e->material.eps_t33 / model::kEps0, complex_loss ? e->eta : e->beta_s};
  Eigen::VectorXd s_rel(5);
  for (int i = 0; i < 5; ++i) {
    OeParameter& p = c.parameters[static_cast<std::size_t>(i)];
    const OeParameter& base = r.parameters[static_cast<std::size_t>(i)];
    const double stat_rel = cov_ok ? std::sqrt(std::max(0.0, c.covariance_rel(i, i))) : NAN;
    // The chain's type-B part of the fit without the effect, relative.
    const double b2 = base.sigma * base.sigma - base.sigma_statistical * base.sigma_statistical;
    const double typeb_rel = base.value != 0 && std::isfinite(b2) ? std::sqrt(std::max(0.0, b2)) / std::abs(base.value) : 0.0;
    const double rel = std::hypot(stat_rel, typeb_rel);
    s_rel[i] = rel;
    p.value = values[i];
    p.sigma = rel * std::abs(p.value);
    p.sigma_statistical = stat_rel * std::abs(p.value);
    p.status = "ok";
    p.reason.clear();
    p.note.clear();
    const double limit = i < 4 ? identifiable_rel_sigma : 0.5;
    char buf[320];
    if (!std::isfinite(rel)) {
      p.status = "not identifiable";
      p.reason = "singular";
      p.note = "the fit with " + effect + " does not constrain it (singular normal equations)";
    } else if (!e->explains) {
      p.status = "not identifiable";
      p.reason = "lack of fit";
      std::snprintf(buf, sizeof buf,
                    "even with %s the model does not explain the capture (chi2/dof %.3g, the noise alone allows "
                    "up to %.3g)",
                    effect.c_str(), e->chi2_per_dof, r.chi2_limit);
      p.note = buf;
    } else if (rel > limit) {
      p.status = "not identifiable";
      p.reason = "sigma";
      std::snprintf(buf, sizeof buf, "relative sigma %.2g %% with %s exceeds the %.2g %% limit", 100 * rel,
                    effect.c_str(), 100 * limit);
      p.note = buf;
    }
  }
  if (complex_loss && c.eta > 0) {
    c.qm = 1.0 / c.eta;
    c.qm_sigma = c.qm * s_rel[4];
  }
  // Correlations of the statistical covariance (the type-B part is small beside it where it matters).
  if (cov_ok) {
    c.correlation = Eigen::MatrixXd::Identity(5, 5);
    for (int a = 0; a < 5; ++a)
      for (int b = 0; b < 5; ++b)
        c.correlation(a, b) = a == b ? 1.0
                                     : c.covariance_rel(a, b) /
                                           std::sqrt(c.covariance_rel(a, a) * c.covariance_rel(b, b));
    c.corr_nu12_d31 = c.correlation(1, 2);
  }
  return c;
}

}  // namespace piezo::update
