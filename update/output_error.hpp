#pragma once
// Output-error estimation of the tube's constants from a divider capture
// (issue 17): the material constants of the model class and the Rayleigh
// damping β are fitted DIRECTLY to the recorded samples — v2 predicted from the
// recorded v1 through R1 and the FE port model (model/port_model.hpp, seed
// eqs 87-92) — instead of going through Prony's features and CMCM's pairing.
//
//   prediction  v̂2 = IDFT[ T_θ(f_k) · DFT[v1] ],  T = 1/(1 + R1·Y_θ(jω))
//               per DFT bin on a zero-padded record (4× the record: the modes'
//               ring-down does not wrap around), i.e. the tube at rest and v1 = 0
//               before the first recorded sample. With a pretrigger that is the
//               truth (the AWG idles); a record that starts AT the step assumes
//               the step happened at its first sample (the drive's onset is v1[0]).
//   residual    r = L ∗ (v̂2 − v2) at every d-th sample, L a causal low-pass
//               FIR (Blackman-windowed sinc at band_hz, unit DC gain),
//               d = fs/(2·band): the modes far above the band (which the step
//               excites and the FE mesh places less well) are left out, and the
//               filtered error is sampled at about its own bandwidth, so its
//               samples are nearly independent (for the covariance);
//   weight      1/σ_r, σ_r the noise the capture itself shows: the scatter of
//               repeated shots, else the pretrigger samples, else the robust
//               high-pass noise estimate of each channel (dsp::estimate_noise_std),
//               propagated through L (and T for v1's noise);
//   fit         θ = (ln YE11, nu12, ln(d31/d31₀), ln εT33, ln β); a coarse
//               stage evaluates a 3×3 grid over YE11 and nu12 (the constants
//               that set the resonance pattern; the others enter the pattern
//               weakly), Levenberg–Marquardt from the best starts on the
//               re-linearised FE port model; the best optimum wins and the
//               spread of the distinct optima is reported.
//   uncertainty cov = s²·(JᵀJ)⁻¹ of the weighted residual, s² = max(1, χ²/ν):
//               a fit worse than the noise (an effect the model class lacks)
//               widens every sigma by the Birge ratio instead of hiding it.
//   honesty     a constant whose relative sigma exceeds `identifiable_rel_sigma`,
//               or whose value differs between the starts' optima by more than
//               3 sigma, is "not identifiable" (with its numbers and what would
//               pin it).
#include <Eigen/Core>
#include <array>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "model/effects.hpp"
#include "model/modal.hpp"
#include "model/transient.hpp"
#include "update/residual_regions.hpp"
#include "update/cmcm.hpp"
#include "update/parametrization.hpp"

namespace piezo::update {

// One recorded divider shot: samples from the record's start (pretrigger
// included), volts.
struct OeShot {
  std::span<const double> v1, v2;
  std::size_t pretrigger = 0;  // samples before the drive starts (0: the record starts at it)
};

struct OeData {
  std::vector<OeShot> shots;  // same rate; shots of equal length and pretrigger are averaged
  double sample_rate_hz = 0;
  model::DividerCircuit circuit;  // R1 (and a measured fixture: Cp, lead R)
  double v2_delay_s = 0;          // channel 2 recorded late by this (a measured skew)
  double mains_hz = 0;            // the bench's mains frequency (/setup mains_hz); 0: unknown (50 and 60 tried)
};

// How the tube's mechanical loss is modelled (issue 19, item 2):
//  rayleigh          C = βK_UU (α = 0): mode k damped by jωβκ_k, ξ_k ∝ ω — the
//                    fifth coordinate is ln β;
//  complex_constants cE·(1 + j/Qm), the hysteretic loss of the piezo-
//                    characterisation programs: jκ_k/Qm per mode (mode k's
//                    Qm_k = Qm·ω_k²/κ_k, independent of frequency) — the fifth
//                    coordinate is ln(1/Qm) (model::tube_admittance's elastic_loss).
enum class OeDamping { rayleigh, complex_constants };
const char* damping_name(OeDamping d);  // "rayleigh" | "complex constants"
// "rayleigh" | "complex" (or "complex constants"); nullopt otherwise.
std::optional<OeDamping> parse_damping(const std::string& s);

// "Rayleigh beta 1.02e-07 s" or "complex constants Qm 95.3 +- 1.2" (displays).
struct OeResult;
std::string damping_summary(const OeResult& r);

// A fitted loss: the model and its one value (β for rayleigh, η = 1/Qm for
// complex constants; the other is 0).
struct OeLoss {
  OeDamping model = OeDamping::rayleigh;
  double beta_s = 0;  // Rayleigh β (s)
  double eta = 0;     // 1/Qm
};

struct OeOptions {
  double band_hz = 0;  // 0: 1.6 × the nominal model's third electrically active mode
  model::ModalOptions modal = [] {
    model::ModalOptions m;
    m.n_modes = 16;
    return m;
  }();
  double beta0_s = 1e-7;  // Rayleigh β to start from (the seed's value)
  // The damping model fitted (OeDamping; the default was chosen by the
  // comparison study, docs/update-methods.md) and, for complex constants, the
  // 1/Qm to start from (Qm = 100, soft PZT; β = 1e-7 s gives the 50 kHz hoop
  // mode Qm ≈ 32).
  OeDamping damping = OeDamping::rayleigh;
  double eta0 = 1e-2;
  // Coarse stage: the grid (1 ± span) over YE11 and nu12; LM from the best `refine` points.
  double grid_span_ye11 = 0.08, grid_span_nu12 = 0.10;
  int refine = 3;
  int max_iterations = 40;
  // The LM trust region of a scanned effect's coordinate, in typical sizes
  // per step (the constants' logs keep their 0.3; μ still damps the step).
  // The constants' 0.3 on it made the scan crawl: 0.3 of a typical size an
  // iteration, 20–30 iterations (an FE port model each) to reach an effect of
  // 6–9 typical sizes (refsim 01), and stop short where the drop per
  // iteration fell under cost_tolerance (docs/benchmarks.md).
  double effect_max_step = std::numeric_limits<double>::infinity();
  // The scan's runs on a surrogate of the FE port model (reduced bases,
  // model/reduced_port.hpp; update/output_error/forward_model.hpp,
  // Problem::set_surrogate), each run's answer evaluated again on exact
  // models with a Gauss–Newton step there: the same answers to within the
  // runs' stopping rule, for a quarter fewer modal solves on the corpus
  // (docs/benchmarks.md). false: every model exact (the comparison of
  // tests/update/test_output_error.cpp).
  bool scan_surrogate = true;
  double step_tolerance = 1e-6;  // converged when max |Δθ| < this …
  double cost_tolerance = 1e-2;  // … or ½χ² dropped by less than this (the answer within ~0.15 sigma)
  // (with the full Jacobian; a scanned effect's run with the constants' columns
  // frozen is a chord method and can stop further off: two settings of its trust
  // region ended up to 2.3 apart in χ², refsim 08's mechanical damping.)
  double identifiable_rel_sigma = 0.05;
  // Systematic (type B) uncertainties of the measurement chain that the
  // samples cannot separate from the constants — R1 and a capacitance across
  // the transducer are exact aliases of the admittance's scale and of C0, a
  // channel gain and skew near ones. Each is propagated to the constants
  // through the fit's sensitivity dθ/db = −(JᵀJ)⁻¹Jᵀ ∂r/∂b and added to their
  // covariance. Defaults: an R1 known to its 1 % tolerance, 30 pF of unmeasured
  // cable/input capacitance, 0.5 % channel-gain mismatch, no skew (simultaneous
  // sampling). A measured fixture (calibration shots) replaces them by its sigmas.
  double r1_rel_sigma = 0.01;
  double cp_sigma_f = 30e-12;
  double gain_rel_sigma = 0.005;
  double skew_sigma_s = 0.0;
  // Lack of fit: χ²/ν above 1 + lack_of_fit_z·sqrt(2/ν + 2/ν_noise) (ν_noise:
  // the degrees of freedom of the noise estimate) means the model class does
  // not explain the capture: every constant is then "not identifiable" (reason
  // "lack of fit"), its sigma widened by the Birge ratio sqrt(χ²/ν).
  double lack_of_fit_z = 4.0;
  // … or a misfit concentrated in frequency: the residual's periodogram over
  // its expected noise shape (scaled by its own median), summed in windows of
  // 1-64 bins; lack of fit when the least likely window's chance under noise
  // alone, times the number of windows tried, is below this. An unmodelled end
  // mass that the constants absorb at χ²/ν ≈ 1 leaves its misfit around the
  // modes it moves (refsim corpus case 02: 4 % added mass, 10^-7.1 in
  // 40-56 kHz at χ²/ν 1.22); noise alone (our 20-tube study) stays above 0.1.
  double lack_of_fit_p = 1e-3;
  // Effects of the catalogue to fit one at a time beside the five (names of
  // model/effects.hpp; empty: none). Each costs an LM run from the optimum;
  // mass_loading builds an FE model per evaluation.
  std::vector<std::string> scan_effects;
  // FE port models built at once where a step needs several (an exact
  // Jacobian's columns, a grid of starts): 2 uses a second modal solver on a
  // second thread; the answers are the same for any count. 1 where the caller
  // already keeps every core busy (a batch replay with --jobs > 1).
  int threads = 2;
  // Slow disturbances (issue 33; update/output_error/baseline.hpp): a baseline
  // (offset, slope, polynomial wander, mains hum) projected out and 1/f noise
  // whitened, each when the data show it at the first optimum (then the
  // starts are refitted under it). false: the white model with the offset
  // alone, as before.
  bool disturbances = true;
  // A held-out prediction weighs its capture's 1/f noise only when this is
  // set (the fit's capture, on the same bench, showed 1/f noise): a
  // prediction's own misfit can look like 1/f noise (prediction.cpp).
  bool heldout_pink = false;
  double effect_significance = 25.0;  // Δχ² (one parameter) beyond this, scaled by χ²/ν when > 1
  double alias_threshold = 0.05;
};

// The FE port models' tangent where a fit ended (its last exact Jacobian's
// models: at x_ref and at x_ref + h·e_c for the four constants, the fit's
// coordinates about `origin`, the end mass `mass`). A held-out prediction near
// there takes its Jacobian's material columns from it (the port model at its
// own point plus the tangent's slopes, checked there: Problem::tangent_near)
// instead of four new FE models per prediction.
struct OePortTangent {
  TubeParams origin;  // the fit's coordinates' constants at x = 0 (the nominal ones)
  Eigen::Vector4d x_ref = Eigen::Vector4d::Zero();
  double mass = 0, h = 0;
  model::ModalPortModel base;
  std::array<model::ModalPortModel, 4> plus;
  std::array<double, 4> slope{};  // the largest relative slope of an active mode's ω or |p| per unit x_c
};

// One catalogue effect (model/effects.hpp) fitted as a sixth parameter beside
// the five, from the five's optimum (issue 18: the gap of any capture, one
// shot included, in the same output-error model as the estimate).
struct OeEffect {
  std::string name, unit;
  double value = 0, sigma = 0;  // SI (daq_input_resistance: ohm, from a fitted conductance)
  double delta_chi2 = 0;        // χ² of the five-parameter fit minus χ² with the effect
  // ‖(I − P)j‖/‖j‖ of the effect's Jacobian column against the five's at their
  // optimum: below OeOptions::alias_threshold the constants mimic the effect
  // (R1's tolerance, a parallel capacitance): never a finding, only a bias.
  double alias_residual = 1;
  bool alias = false;
  // ‖(I − P)j‖ at `typical` in noise units: the Δχ² would be its square for
  // an effect of the typical size (what this capture can see of it).
  double detectability = 0;
  // What the constants take of it when it is not modelled: their shift, %,
  // for `typical` (SI) of the effect (YE11, nu12, d31, εT33).
  double typical = 0;
  double bias_pct[4] = {0, 0, 0, 0};
  bool significant = false;  // Δχ² beyond OeOptions::effect_significance·max(1, χ²/ν), physical value
  bool explains = false;     // significant, and with it no lack of fit is left
  double chi2_per_dof = 0, band_log10_p = 0;  // with the effect
  bool converged = false;
  // Not refitted: its score at the optimum (the first-order Δχ²) was below a
  // quarter of the significance, so value, σ and Δχ² are the linear ones.
  bool linearised = false;
  TubeParams material;  // the constants refitted with it
  double beta_s = 0;    // … and the Rayleigh β (0 with complex constants)
  double eta = 0;       // … or 1/Qm (complex constants; 0 with Rayleigh)
  OeDamping damping_model = OeDamping::rayleigh;
  OeLoss loss() const { return {damping_model, beta_s, eta}; }
  // The whole effect set of the fit with it (the bench's known effects and
  // this one at its value): what predicts another capture with it.
  model::EffectSet effect_set;
  // The fit's statistical covariance with it, relative coordinates as
  // OeResult::covariance_rel plus the effect's (effect_coordinate units).
  Eigen::MatrixXd covariance_rel;
  // dielectric_loss: the law in frequency that fitted better (both are tried):
  // "frequency-independent" (εT33·(1 − j·tanδ), the FE convention) or
  // "constant-phase" (causal, ε' falling with frequency).
  std::string law;
  int fe_models = 0;  // FE port models its scan built (the refit, both laws, the extra starts)
  // The port models' tangent where its refit ended (null: linearised, or none).
  std::shared_ptr<const OePortTangent> port_tangent;
};

struct OeParameter {
  std::string name, unit;
  double value = 0, sigma = 0;
  double nominal = 0;
  double sigma_statistical = 0;  // from the noise alone (Birge-widened), without the type-B part
  std::string status;  // "ok" | "not identifiable"
  std::string reason;  // when not identifiable: "sigma" | "starts" | "lack of fit" | "singular"
  std::string note;    // why not identifiable, and what would pin it
};

// The slow disturbances the fit found and modelled (issue 33 item 1). The
// residual sees the DIFFERENCE of the channels' baselines (T ≈ 1 at their
// frequencies: channel 1's reaches the prediction of v2 unchanged), so the
// slope and hum are of channel 1 minus channel 2; each channel's offset is
// its pretrigger's mean, where the record has one.
struct OeBaselineShot {
  int shot = 0;                      // index among the shots averaged
  double offset_v = 0, slope_v_per_s = 0, hum_v = 0;
};
struct OeBaseline {
  bool modelled = false;             // the baseline's columns were projected out
  double delta_chi2 = 0;             // χ² its columns took beyond the offset's (at the first optimum)
  int dof = 0;                       // their number beyond the offset
  double log10_p = 0;                // chance of that under white noise (Bonferroni over the mains tried)
  int poly_degree = 0;
  double mains_hz = 0;               // the hum's frequency in the columns (0: none)
  bool mains_known = false;          // from the capture's /setup
  bool mains_distinguishable = false;  // 50 and 60 Hz told apart by the data
  int harmonics = 0;                 // hum harmonics in the columns (0: record below half a mains cycle)
  // Channel 1 minus channel 2, the shots averaged (volts, V/s), with sigmas;
  // NaN where not in the model.
  double offset_v = 0, offset_sigma_v = 0;          // beyond the pretrigger's means
  double slope_v_per_s = 0, slope_sigma_v_per_s = 0;
  double hum_v = std::numeric_limits<double>::quiet_NaN(), hum_sigma_v = std::numeric_limits<double>::quiet_NaN();
  bool channel_offsets = false;      // from a pretrigger
  double channel_offset_v[2] = {0, 0}, channel_offset_sigma_v[2] = {0, 0};
  // 1/f noise.
  bool pink = false;
  double pink_ratio = 0;             // its power over the white floor's at the record's first bin (1/T)
  double pink_rms_v = 0;             // its rms in the filtered residual
  double pink_delta_2lnl = 0;        // the Whittle likelihood's gain from it
  double transfer_error_chi2 = 0;    // χ² of the first optimum's residual along generic transfer errors (a bench effect's)
  std::vector<OeBaselineShot> shots;  // per shot (two or more)
  bool any() const { return modelled || pink; }
};

// The shots' consistency before pooling (issue 33 item 2): each shot's
// constants, linearised about the pooled answer (one Gauss–Newton step of the
// shot's own residual on the answer's Jacobian), weighted by one shot's noise
// measured as the shots' scatter orthogonal to the constants' directions (a
// drift or step of the constants does not inflate it). Their homogeneity χ², and
// per constant the better of a linear drift over the shots and a step between
// two of them.
struct OeShotChange {
  std::string parameter;  // YE11, nu12, d31, epsT33_rel, beta | qm_inverse
  std::string kind;       // "drift" | "step"
  double size_pct = 0, sigma_pct = 0;  // drift: last shot minus first, along the fitted line; step: after minus before
  int after_shot = -1;    // step: between this shot and the next (indices among OeData::shots)
  double z = 0;           // size / sigma
};
struct OeShotConsistency {
  bool tested = false;    // two or more shots averaged
  int shots = 0;
  double chi2 = 0;        // homogeneity of the per-shot constants against their sigmas
  int dof = 0;
  double log10_p = 0;
  bool consistent = true;  // chance above 1e-6 (shot_consistency.cpp: why not 1e-3)
  std::vector<std::vector<double>> per_shot_pct;  // each shot's constants, % from the pooled answer
  std::vector<double> per_shot_sigma_pct;         // one shot's sigma of each constant, %
  std::vector<OeShotChange> changes;              // the significant drifts and steps, largest z first
  std::string summary;                            // one sentence ("" when consistent)
  // Trigger jitter: each averaged shot's delay against the first (samples),
  // and whether they were aligned before averaging (any beyond 0.1 sample).
  std::vector<double> jitter_samples;
  bool aligned = false;
};

struct OeResult {
  UpdateStatus status = UpdateStatus::bad_input;
  std::string message;
  TubeParams original, updated;
  model::RayleighDamping damping;  // fitted β (α = 0); β = 0 with complex constants
  // The damping model fitted (OeOptions::damping) and, with complex
  // constants, the fitted loss as Qm = 1/η with its sigma (statistical and
  // type B as the other parameters'; NaN/inf with Rayleigh).
  OeDamping damping_model = OeDamping::rayleigh;
  double eta = 0;  // 1/Qm (complex constants)
  double qm = std::numeric_limits<double>::infinity(),
         qm_sigma = std::numeric_limits<double>::quiet_NaN();
  OeLoss loss() const { return {damping_model, damping.beta, eta}; }
  // YE11, nu12, d31, epsT33_rel, then "beta" (Rayleigh) or "qm_inverse" (1/Qm, complex constants)
  std::vector<OeParameter> parameters;
  Eigen::MatrixXd correlation;              // same order as parameters
  double corr_nu12_d31 = 0;
  double band_hz = 0;
  int shots_used = 0;
  std::string noise_source;                 // "shots" | "pretrigger" | "high-pass estimate"
  std::string offset_model;                 // how the DAQ offsets enter (pretrigger / unknown / the baseline's projection)
  OeBaseline baseline;                      // the slow disturbances found (issue 33)
  OeShotConsistency shot_consistency;       // the shots' agreement before pooling (issue 33)
  double noise_rms_v = 0;                   // σ_r of the filtered residual samples
  double residual_rms_v = 0;                // of the filtered residual at the optimum
  double chi2_per_dof = 0;                  // (residual/noise)² per degree of freedom
  double chi2_limit = 0;                    // the lack-of-fit threshold for chi2_per_dof
  double noise_dof = 0;                     // degrees of freedom of the noise estimate
  bool lack_of_fit = false;
  // The band test: the least likely window of the residual's spectrum.
  double band_log10_p = 0;                  // its chance under noise alone (Bonferroni), log10
  double band_excess = 1;                   // residual power / expected noise power in it
  double band_lo_hz = 0, band_hi_hz = 0;    // where it lies
  int band_windows = 0;
  // Under a lack of fit: where the residual stands above the noise and what
  // it looks like there (update/residual_regions.hpp), most significant first.
  std::vector<ResidualRegion> regions;
  int residual_samples = 0;
  int starts = 0, iterations = 0, evaluations = 0;
  std::vector<OeEffect> effects;             // OeOptions::scan_effects, largest Δχ² first
  model::EffectSet effect_set;               // the bench's known effects the fit held (a measured fixture's)
  // Statistical covariance (Birge-widened, no type-B part) of the fit's
  // coordinates at the answer, RELATIVE to it: ln YE11, nu12/nu12 − 1, ln d31,
  // ln εT33, ln β or ln(1/Qm) (what the held-out prediction propagates).
  Eigen::MatrixXd covariance_rel;
  // The port models' tangent near the answer (the held-out predictions'
  // Jacobian; null when the fit left none).
  std::shared_ptr<const OePortTangent> port_tangent;
  std::vector<TubeParams> optima;            // every refined start's optimum (best first)
  std::vector<double> optima_cost;
  double seconds = 0;
  // The chain tolerances the sigmas hold (OeOptions, or a measured fixture's).
  double r1_rel_sigma = 0, cp_sigma_f = 0, gain_rel_sigma = 0, skew_sigma_s = 0;
  bool ok() const { return status == UpdateStatus::converged; }
};

// Throws std::invalid_argument for unusable data (no shots, lengths that do
// not match, non-finite samples, a band above Nyquist); a fit that does not
// converge is a status with a message.
OeResult fit_output_error(model::ModalSolver& solver, const MaterialClass& cls,
                          const TubeParams& nominal, const OeData& data,
                          const OeOptions& options = {});

// A catalogue effect as a coordinate of the output-error model: x units of
// model::effect_coordinate_unit added to its EffectSet field (a conductance
// coordinate, the DAQ input, as x·1 µS, so that 0 is "none"). Empty for
// effects this model cannot fit.
struct EffectCoordinate {
  std::function<void(model::EffectSet&, double)> apply;
};
std::optional<EffectCoordinate> effect_coordinate(const std::string& name);

// The held-out check (issue 18): another capture of the same transducer —
// any drive, one shot or more — its v2 predicted from its own v1 by given
// constants, Rayleigh β and bench effects, nothing fitted; the filtered
// residual (same low-pass, decimation, offset handling and noise sources as
// the fit) against that capture's own noise.
struct OePrediction {
  double chi2_per_dof = 0;  // (residual/noise)² per degree of freedom
  int samples = 0;          // filtered residual samples
  double dof = 0;           // samples minus the offsets' projected dimension
  double noise_rms_v = 0, residual_rms_v = 0;
  double noise_dof = 0;     // degrees of freedom of the noise estimate
  double chi2_limit = 0;    // chi2_per_dof beyond this: the prediction misses (OeOptions::lack_of_fit_z)
  int shots_used = 0;
  bool prediction_uncertainty = false;  // the fit's covariance was counted (see below)
  // Where a prediction without an effect that misses (χ²/ν beyond its limit)
  // stands above the noise, and what it looks like there
  // (update/residual_regions.hpp).
  std::vector<ResidualRegion> regions;
  std::string noise_source, offset_model;
  OeBaseline baseline;  // the held-out capture's own slow disturbances
};

// What predictions on one held-out record may share (predict_output_error's
// `shared`, one per diagnosis: gap_output_error): the filtered baseline
// columns of its slow disturbances, which depend on the record's shape and the
// band alone, computed once for all of them whichever thread asks first. A
// prediction on a record of another shape or band keeps its own.
struct OeRecordShare;
std::shared_ptr<OeRecordShare> make_record_share();

// Throws std::invalid_argument for unusable data (as fit_output_error) and
// std::runtime_error when the model cannot be simulated.
//
// With `covariance_rel` (OeResult/OeEffect::covariance_rel) the prediction's
// own uncertainty counts as noise: χ² = min_θ ‖r(θ)/σ‖² + (θ − θ̂)ᵀC⁻¹(θ − θ̂)
// over the fit's coordinates (and the effect's, `effect`), to first order
// rᵀ(σ²I + J·C·Jᵀ)⁻¹r — a held-out record far richer than the fit's (a chirp)
// sees the fit's constants' sigmas, which are no gap.
OePrediction predict_output_error(model::ModalSolver& solver, const MaterialClass& cls, const TubeParams& params,
                                  double beta_s, const model::EffectSet& effects, const OeData& data,
                                  double band_hz, const OeOptions& options = {},
                                  const Eigen::MatrixXd& covariance_rel = {},
                                  const std::string& effect = "");
// The same with the fit's damping model (OeResult/OeEffect::loss()): a held-out
// prediction must use the damping model that was fitted.
OePrediction predict_output_error(model::ModalSolver& solver, const MaterialClass& cls,
                                  const TubeParams& params, const OeLoss& loss,
                                  const model::EffectSet& effects, const OeData& data,
                                  double band_hz, const OeOptions& options = {},
                                  const Eigen::MatrixXd& covariance_rel = {},
                                  const std::string& effect = "",
                                  const std::shared_ptr<OeRecordShare>& shared = nullptr,
                                  const std::shared_ptr<const OePortTangent>& tangent = nullptr);

}  // namespace piezo::update
