#pragma once
// The seed's chain held to the output-error fit's standard (issue 40): extended
// CMCM (§6.3-6.4) or least squares on measured features, then an honest status.
//
// A method's own stopping test says nothing about physics. `converged` here
// means all of
//   * every feature used lies inside the band the drive covers and the model's
//     mode range (FeatureBand) and was measured with a σ;
//   * the method itself converged;
//   * the constants are physical (PhysicalBounds: a PZT ceramic);
//   * the updated model reproduces the features it was given: χ² of
//     (model − measured)/σ over n − 4 degrees of freedom not beyond the chance
//     `chi2_chance` (with no degree of freedom left: every |z| ≤ 3);
//   * every constant determined: relative σ ≤ 5 % (the output-error fit's rule).
// Otherwise the status is `no_features`, the method's own failure
// (`max_iterations`, `ambiguous_pairing`, …), `non_physical` or
// `not_identifiable`, with the reason in words.
//
// Every constant carries a σ: the features' σ propagated —
//   least squares: Cov(ln p) = (AᵀA)⁻¹, A_ik = (f_i/σ_i)·∂ln f_i/∂ln p_k (the
//     weighted estimator's covariance; ∂ by central differences of the FE model);
//   extended CMCM (unweighted, phase by phase): the delta method through the
//     method itself — one re-solve per feature moved by its σ — and never below
//     the least-squares bound above (a direction the features do not determine
//     has no σ from a minimum-norm TSVD answer).
// σ's are widened by the Birge ratio sqrt(χ²/ν) when it exceeds 1. εT33 also
// comes from the low-frequency capacitance alone (the other constants held at
// the nominal ones: C^T of a free tube is εT33's, eq. 200-201), reported even
// when the resonances fail.
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "model/modal.hpp"
#include "model/tube_model.hpp"
#include "update/features.hpp"
#include "update/least_squares.hpp"
#include "update/parametrization.hpp"
#include "update/updater.hpp"

namespace piezo::update {

// Where a feature may lie: the drive's band ∩ the model's mode range.
struct FeatureBand {
  double lo_hz = 0, hi_hz = 0;
  std::string source;  // in words: what set each edge
  bool contains(double f_hz) const { return f_hz >= lo_hz && f_hz <= hi_hz; }
};

// What a PZT ceramic's four constants can be (docs: honest-uncertainty §3).
struct PhysicalBounds {
  double y_e11_min = 20e9, y_e11_max = 200e9;  // Pa
  double nu12_min = 0.0, nu12_max = 0.5;
  double d31_abs_min = 1e-12, d31_abs_max = 1e-9;  // C/N
  double eps_t33_rel_min = 100, eps_t33_rel_max = 10000;
  double k31_max = 0.75;  // |d31|·sqrt(YE11/εT33): PZT ceramics up to about 0.75
  std::string material_class = "PZT ceramic";
};

struct FeatureCheckOptions {
  double chi2_chance = 1e-3;
  double max_relative_sigma = 0.05;
  PhysicalBounds bounds;
};

// One constant: value, σ (Birge-widened), "ok" | "not identifiable" and why.
struct ConstantEstimate {
  std::string name, unit;
  double value = 0, sigma = 0, sigma_statistical = 0;
  std::string status, reason, note;
};

struct FeatureResidual {
  std::string kind;  // resonance | antiresonance | capacitance
  int index = 0;
  double measured = 0, sigma = 0, model = 0;  // Hz, or F for the capacitance
  double z = 0;                               // (model − measured)/σ
};

// What check_feature_update judges (constructed by update_from_features, or by hand in a test).
struct FeatureCheckInput {
  MeasuredFeatures measured;  // the features the method used, with σ
  FeatureBand band;
  std::vector<double> model_resonances_hz, model_antiresonances_hz;  // updated model, in order
  double model_capacitance_f = 0;                                    // updated model at low_z_hz
  TubeParams updated;
  std::array<double, 4> sigma{};  // statistical σ of YE11, nu12, d31, εT33 (absolute; inf: not determined)
  int fitted = 4;                 // constants fitted: χ² has n − fitted degrees of freedom
  std::string method_status = "converged", method_message;
};

struct FeatureCheck {
  std::string status;  // converged | no_features | non_physical | not_identifiable | the method's own
  std::string reason;
  std::vector<FeatureResidual> residuals;
  double chi2 = 0;
  int dof = 0;
  double log10_chance = 0;  // log10 P(χ²_ν ≥ chi2) (0 when not tested)
  double birge = 1;         // the σ's widening, sqrt(χ²/ν) when > 1
  std::vector<ConstantEstimate> constants;  // YE11, nu12, d31, epsT33_rel
  bool converged() const { return status == "converged"; }
};

FeatureCheck check_feature_update(const FeatureCheckInput& in, const FeatureCheckOptions& opt = {});

enum class FeatureMethod { cmcm, lm };
const char* to_string(FeatureMethod m);

struct FeatureUpdateOptions {
  UpdateOptions cmcm = [] {
    UpdateOptions o;
    // Measured features are not exactly reachable (noise; three resonances for
    // two stiffnesses): the sweeps settle to a least-squares point slowly.
    o.max_sweeps = 40;
    o.sweep_tolerance = 1e-6;
    return o;
  }();
  LmOptions lm;
  FeatureCheckOptions check;
};

struct FeatureUpdate {
  FeatureMethod method = FeatureMethod::cmcm;
  std::string method_status, method_message;  // what the method itself said
  TubeParams updated;                         // the method's answer (p0 when it did not run)
  FeatureCheck check;                         // the honest status and the constants with σ
  MeasuredFeatures used;
  // εT33 from the low-frequency capacitance alone (others nominal), with σ.
  double eps_t33_from_c = 0, eps_t33_from_c_sigma = 0;
  int resolves = 0, resolves_failed = 0;  // CMCM's delta method
  double seconds = 0;
  std::optional<UpdateResult> cmcm;
  std::optional<LmResult> lm;
  bool ok() const { return check.converged(); }
};

// `features` may hold no resonance or anti-resonance (then only εT33 is
// determined, status no_features with `no_features_reason`). Never throws for
// features the method cannot use; throws std::invalid_argument for a
// non-physical p0.
FeatureUpdate update_from_features(const model::TubeModel& tube, model::ModalSolver& solver,
                                   const MaterialClass& cls, const TubeParams& p0,
                                   const MeasuredFeatures& features, const FeatureBand& band,
                                   FeatureMethod method, const FeatureUpdateOptions& opt = {},
                                   const std::string& no_features_reason = "");

}  // namespace piezo::update
