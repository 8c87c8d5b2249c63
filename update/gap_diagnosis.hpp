#pragma once
// The sim-to-real gap after updating (issue 7): how far the updated model
// still is from the measurement, where in frequency, of what kind, which
// unmodelled effect of the catalogue (model/effects.hpp) explains it, and how
// much it shrinks once that effect is added — judged on held-out data.
//
//  1. Base fit: the four material parameters + Rayleigh α, β refitted to the
//     whole measured Z(f) (update/gap_fit.hpp), starting from the CMCM
//     update. Its χ² against the measurement's own noise is the gap; a gap
//     within 3σ of χ²'s spread is "no gap".
//  2. Where: the base misfit by region (capacitive band, each resonance and
//     anti-resonance neighbourhood, the bands between, the high-frequency
//     tail), each with its share of χ² and a decomposition into frequency
//     shift, peak width/height, level and phase.
//  3. Identifiability: an effect whose Jacobian column lies (almost) in the
//     span of the material + damping columns is an ALIAS: the impedance alone
//     cannot tell it from a change of constants; it is reported with the
//     bias it would put on them, never as a gap.
//  4. Which: every identifiable effect refitted together with material and
//     damping; value ± σ, Δχ² (significant only beyond a 5σ penalty scaled
//     by the remaining misfit), and the held-out shrink 1 − g_after/g_before
//     of the excess gap g = √max(0, χ²/N − 1) on data the fit never saw.
//     Greedy: the best significant effect is added and the rest refitted, at
//     most `max_effects` times.
//  The decisions both gap paths share — the shrink, the held-out check, the
//  verdict's effect, the sentences — are the diagnosis core's
//  (update/gap_core.hpp); this path computes the impedance residual's evidence.
#include <atomic>
#include <cmath>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "update/gap_fit.hpp"
#include "update/gap_regions.hpp"

namespace piezo::update {

struct EffectReport {
  std::string name, unit;
  bool alias = false;
  double alias_residual = 0;  // ‖(I − P)j‖/‖j‖: 0 = mimicked exactly by the constants
  double detectability = 0;   // ‖(I − P)j‖ at the typical magnitude, in σ units
  double typical = 0;         // SI, the magnitude the two numbers above refer to
  // Bias on the refitted constants that a typical magnitude would cause, %.
  double bias_y_e11_pct = 0, bias_nu12_pct = 0, bias_d31_pct = 0, bias_eps_t33_pct = 0;
  bool fitted = false;
  double value = 0, sigma = 0;  // SI
  double chi2_after = 0, delta_chi2 = 0, shrink_fit = 0;
  bool significant = false;
  std::optional<double> heldout_chi2_after, heldout_shrink;
  TubeParams material;  // refitted with the effect
  // Its relative standard errors (YE11, nu12, d31, εT33), scaled by
  // max(1, χ²/dof) as GapFit::sigma_x; NaN where the refit had none.
  double material_rel_sigma[4] = {NAN, NAN, NAN, NAN};
  // Other candidates whose signature, after the constants took what they can,
  // points the same way (|cos| >= GapOptions::indistinguishable_cos): this
  // data cannot tell them from this one.
  std::vector<std::string> indistinguishable_from;
  std::string note;
};

// An effect measured independently of the impedance (the fixture
// calibration of issue 10: open/short/load shots in the capture). It enters
// the model at its value and is reported as measured, not fitted or aliased.
struct MeasuredEffect {
  std::string name;  // catalogue name (model/effects.hpp)
  double value = 0, sigma = 0;  // SI; sigma 0: not known
  std::string source;
};

struct GapCurve {  // misfit ln(Z_meas/Z_model) for plots
  std::vector<double> f_hz, residual_db, residual_deg, sigma_db, sigma_deg;
  std::vector<double> measured_abs_ohm;  // |Z_meas|; the model's |Z| is |Z_meas|·10^(−residual_db/20)
};

struct GapDiagnosis {
  // "impedance": Z(f) of repeated shots (diagnose_gap); "output-error": the
  // samples of one or two shots (update/gap_output_error.hpp).
  std::string method = "impedance";
  bool gap = false;  // significant on the fit data or the held-out data
  double chi2_fit = 0;
  int n_fit = 0, dof_fit = 0;
  double gap_fit = 0;  // √(χ²/dof): 1 = at the noise
  std::optional<double> chi2_heldout, gap_heldout;
  int n_heldout = 0;
  std::string fit_description, heldout_description;
  TubeParams material_base;            // base refit
  model::RayleighDamping damping_base;
  std::vector<GapRegion> regions;      // of the base misfit
  std::vector<MeasuredEffect> measured;  // in the model at their measured values (not candidates)
  std::vector<EffectReport> effects;   // first round, ranked best first; aliases last
  std::vector<std::string> added;      // greedy selection, in order
  std::vector<EffectReport> steps;     // the fit of each added effect (in the model with the previous ones)
  std::optional<double> heldout_shrink;  // of all added effects together
  GapCurve before, after;              // base model, and with the added effects
  // The held-out data showed no gap of their own: the verdict's effect was
  // checked not to worsen them (no held-out shrink to report: heldout_shrink empty).
  bool heldout_without_gap = false;
  // The base refit started from GapOptions::other_starts fitted better than
  // from the updated constants (the update had failed to find them).
  bool base_from_other_start = false;
  std::string verdict_effect;          // "none", an effect name (first added), or "unexplained"
  std::vector<std::string> verdict_alternatives;  // indistinguishable from the verdict's effect on this data
  // The bench's slow disturbances found in the fit data (issue 33: baseline
  // wander, mains hum, 1/f noise), modelled as nuisance — findings of their
  // own, never an effect of the catalogue. One sentence each.
  std::vector<std::string> disturbances;
  std::string verdict;                 // one sentence for the technician
  double seconds = 0;
};

struct GapOptions {
  std::vector<std::string> candidates;  // empty: every effect the model supports
  // Other starting points of the material for the base refit (e.g. the
  // nominal material the update started from), tried when the refit from the
  // updated constants leaves a gap: an update that failed (a mode pairing the
  // CMCM could not make, a least-squares fallback in another basin) must not
  // become a gap that the diagnosis then blames on an effect.
  std::vector<TubeParams> other_starts;
  int max_effects = 3;
  double alias_threshold = 0.05;        // alias_residual below this → alias
  double min_effect_sigma = 3.0;         // |fitted effect − neutral| / σ needed to count (see gap_diagnosis.cpp)
  double significance = 25.0;           // Δχ² (1 dof) beyond this, scaled by χ²/dof if > 1
  double min_heldout_shrink = 0.3;
  double gap_tolerance = 0.3;           // χ²/N beyond 1 + this (and 3σ) is a gap      // an effect must shrink the held-out gap this much to be added
  double damping_ref_hz = 50e3;
  std::vector<MeasuredEffect> measured;  // fixed in the model, removed from the candidates
  double indistinguishable_cos = 0.95;   // see EffectReport::indistinguishable_from
  GapFitOptions fit;
};

// The measured data: `fit` (the capture the update used) and optionally
// `heldout` (another capture or other shots of the same transducer).
// Throws std::invalid_argument for bad data and std::runtime_error when the
// FE model fails; checks `cancel` between candidates.
GapDiagnosis diagnose_gap(model::ModalSolver& solver, const MaterialClass& cls, const TubeParams& start,
                          const model::RayleighDamping& damping_start, double r1_nominal_ohm, const GapData& fit,
                          const GapData* heldout, const GapOptions& opt = {},
                          const std::function<void(double, const std::string&)>& progress = {},
                          const std::atomic<bool>* cancel = nullptr);

// Effects GapModel can fit (the catalogue minus those the model cannot represent).
std::vector<std::string> supported_gap_effects();

}  // namespace piezo::update
