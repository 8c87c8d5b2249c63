// The held-out check (update/output_error.hpp, issue 18): another capture's
// v2 predicted from its own v1 by given constants, loss and effects, its
// filtered residual against that capture's own noise — the fit's covariance
// counted as a penalty on the constants (a few Gauss-Newton steps).
#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>

#include "numerics/gauss_newton.hpp"
#include "update/output_error.hpp"
#include "update/output_error/baseline.hpp"
#include "update/output_error/common.hpp"
#include "update/output_error/forward_model.hpp"
#include "update/output_error/noise.hpp"
#include "update/output_error/shot_average.hpp"
#include "update/residual_regions.hpp"

namespace piezo::update {

std::shared_ptr<OeRecordShare> make_record_share() { return std::make_shared<OeRecordShare>(); }

OePrediction predict_output_error(model::ModalSolver& solver, const MaterialClass& cls, const TubeParams& params,
                                  double beta_s, const model::EffectSet& effects, const OeData& data,
                                  double band_hz, const OeOptions& opt, const Eigen::MatrixXd& covariance_rel,
                                  const std::string& effect) {
  return predict_output_error(solver, cls, params, OeLoss{OeDamping::rayleigh, beta_s, 0.0},
                              effects, data, band_hz, opt, covariance_rel, effect);
}

OePrediction predict_output_error(model::ModalSolver& solver, const MaterialClass& cls,
                                  const TubeParams& params, const OeLoss& loss,
                                  const model::EffectSet& effects, const OeData& data,
                                  double band_hz, const OeOptions& opt,
                                  const Eigen::MatrixXd& covariance_rel,
                                  const std::string& effect, const std::shared_ptr<OeRecordShare>& shared,
                                  const std::shared_ptr<const OePortTangent>& tangent) {
  using namespace oe;
  const double fs = data.sample_rate_hz;
  if (!(fs > 0) || !std::isfinite(fs)) fail("sample rate must be positive");
  data.circuit.validate();
  if (!(band_hz > 0) || !(band_hz < fs / 4)) fail("band above a quarter of the held-out capture's sample rate");
  const Averaged rec = average(data);
  if (rec.v1.size() < 256) fail("too short: " + std::to_string(rec.v1.size()) + " samples (need 256)");
  const Coordinates5 co{params, loss.model == OeDamping::complex_constants ? loss.eta : loss.beta_s,
                        loss.model};
  Problem prob(solver, cls, co, rec, data, band_hz, opt.modal, shared);
  prob.share_columns(shared);
  // The fit's port tangent near these constants: the Gauss–Newton steps below
  // take the material columns of their Jacobian from it (tangent_near checks
  // it at the prediction's point) instead of four FE models per prediction.
  if (tangent) prob.adopt_tangent(*tangent);
  const Eigen::VectorXd x = Eigen::VectorXd::Zero(kParams);
  const auto t = prob.transfer(x, effects);
  if (!t) throw std::runtime_error("predict_output_error: the model cannot be simulated");
  OePrediction out;
  out.shots_used = rec.shots;
  const RecordNoise noise = record_noise(prob, rec, *t);
  double sigma = noise.sigma;
  out.noise_source = noise.source;
  out.noise_dof = noise.dof;
  if (!(sigma > 0) || !std::isfinite(sigma)) fail("the held-out capture shows no measurable noise");
  OffsetWhitening whiten(prob, rec, *t, sigma);
  if (opt.disturbances) {
    // The held-out capture's own slow disturbances (baseline.hpp), at the
    // prediction: its baseline and 1/f noise are its own, never the fit's.
    // Its baseline only: a prediction's misfit is not a fit's residual — a
    // chirp sweeping through a bench effect's band leaves a broad low-
    // frequency excess that reads as 1/f noise 1e4 times the white floor
    // (test_gap_output_error's 30 ohm lead), which the 1/f weighting would
    // hide. It is weighted only where the fit's own capture, on the same
    // bench, showed 1/f noise (OeOptions::heldout_pink).
    DisturbanceModel d = decide_disturbances(prob, rec, *t, prob.residual_of(*t), sigma, noise.ch1, noise.ch2, fs,
                                             data.mains_hz);
    d.pink = d.pink && opt.heldout_pink;
    whiten.use(d, prob, rec, *t);
    out.baseline = report_disturbances(d, whiten.pink.get(), whiten.columns, prob, rec, *t, sigma, 1.0);
  }
  out.offset_model = whiten.model;
  const Eigen::VectorXd r = whiten(prob.residual_of(*t)) / sigma;
  out.samples = static_cast<int>(r.size());
  out.dof = std::max(1.0, double(r.size()) - whiten.dof);
  out.noise_rms_v = sigma;
  out.residual_rms_v = sigma * std::sqrt(r.squaredNorm() / double(std::max<Eigen::Index>(1, r.size())));
  double chi2 = r.squaredNorm();
  // The prediction's uncertainty: the fit's constants may sit anywhere their
  // covariance C allows. χ² = min over θ of ‖r(θ)‖² + (θ − θ̂)ᵀC⁻¹(θ − θ̂) —
  // to first order rᵀ(I + W·C·Wᵀ)⁻¹r (W the held-out Jacobian), but a fit of
  // a few-percent-noise shot has sigmas a rich held-out record does not see
  // linearly: a few Gauss-Newton steps of the penalised problem.
  const Eigen::Index np = covariance_rel.rows();
  const auto coord = effect.empty() ? std::nullopt : effect_coordinate(effect);
  Eigen::VectorXd z = Eigen::VectorXd::Zero(kParams);  // the constants where the held-out data put them
  if ((np == kParams || (np == kParams + 1 && coord)) && covariance_rel.cols() == np && covariance_rel.allFinite()) {
    // C⁻¹ on C's positive eigenvalues (a covariance from a nearly singular
    // JᵀJ can carry rounding-negative ones; a direction C does not constrain
    // gets no penalty-free freedom: its eigenvalue is floored).
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(0.5 * (covariance_rel + covariance_rel.transpose()));
    const double lmax = es.eigenvalues().cwiseAbs().maxCoeff();
    const Eigen::VectorXd lam = es.eigenvalues().cwiseMax(1e-12 * lmax + 1e-300);
    const Eigen::MatrixXd cinv = es.eigenvectors() * lam.cwiseInverse().asDiagonal() * es.eigenvectors().transpose();
    auto residual_at = [&](const Eigen::VectorXd& z) -> std::optional<Eigen::VectorXd> {
      model::EffectSet fx = effects;
      if (np > kParams) coord->apply(fx, z[kParams]);
      const auto tz = prob.transfer(z.head(kParams), fx);
      if (!tz) return std::nullopt;
      Eigen::VectorXd rz = whiten(prob.residual_of(*tz)) / sigma;
      if (!rz.allFinite()) return std::nullopt;
      return rz;
    };
    numerics::PenalisedGnProblem gn;
    gn.residual = residual_at;
    gn.jacobian = [&](const Eigen::VectorXd& z, const Eigen::VectorXd& rz) -> std::optional<Eigen::MatrixXd> {
      Eigen::MatrixXd w(rz.size(), np);
      // The constants' columns through the port models' tangent (Problem::set_tangent).
      model::EffectSet fz = effects;
      if (np > kParams) coord->apply(fz, z[kParams]);
      const Eigen::VectorXd zm = z.head(kParams);
      const bool tangent = prob.tangent_near(zm, fz.mass_loading);
      for (Eigen::Index c = 0; c < np; ++c) {
        const double h = c >= 4 ? 1e-4 : 1e-6;
        if (c < 4 && tangent)
          if (const auto tt = prob.tangent_transfer(zm, static_cast<int>(c), h, fz)) {
            const Eigen::VectorXd rt = whiten(prob.residual_of(*tt)) / sigma;
            if (rt.allFinite()) {
              w.col(c) = (rt - rz) / h;
              continue;
            }
          }
        Eigen::VectorXd zp = z;
        zp[c] += h;
        const auto rp = residual_at(zp);
        if (!rp) return std::nullopt;
        w.col(c) = (*rp - rz) / (zp[c] - z[c]);
      }
      if (!tangent) prob.set_tangent(zm, 1e-6, fz.mass_loading);
      return w;
    };
    // Converged when a step gains less than a thousandth of χ²/ν.
    const auto gr = numerics::penalised_gauss_newton(gn, cinv, Eigen::VectorXd::Zero(np), r, chi2,
                                                     {.max_iterations = 4, .max_halvings = 4, .min_drop = 1e-3 * out.dof});
    z = gr.z;
    const double cost = gr.cost;
    if (std::isfinite(cost) && cost >= 0) {
      chi2 = cost;
      out.prediction_uncertainty = true;
    }
  }
  if (!std::isfinite(chi2)) throw std::runtime_error("predict_output_error: the prediction is not finite");
  out.chi2_per_dof = chi2 / out.dof;
  out.chi2_limit = 1.0 + opt.lack_of_fit_z * std::sqrt(2.0 / out.dof + (out.noise_dof > 0 ? 2.0 / out.noise_dof : 0.0));
  // Where the prediction misses (issue 21): the held-out data of another
  // drive often show what the fit's own record cannot. Only the prediction
  // without an effect is located (gap_output_error.cpp reads no other).
  if (effect.empty() && out.chi2_per_dof > out.chi2_limit) {
    model::EffectSet fz = effects;
    if (z.size() > kParams && coord) coord->apply(fz, z[kParams]);
    if (const auto rs = prob.residual_spectrum(z.head(kParams), fz, noise.ch1, noise.ch2))
      out.regions = residual_regions(*rs, 2, opt.lack_of_fit_p);
  }
  return out;
}

}  // namespace piezo::update
