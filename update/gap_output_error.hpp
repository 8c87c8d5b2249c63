#pragma once
// The gap of a capture diagnosed in the output-error model (issue 18): for
// captures the impedance-domain diagnosis (gap_diagnosis.hpp) cannot take —
// one or two shots, where Z(f)'s noise cannot be measured from repeats and,
// per bin, is not Gaussian at a few percent noise — the catalogue's effects
// are fitted one at a time as a sixth parameter of the time-domain fit
// (OeOptions::scan_effects, update/output_error.hpp) and the result is
// reported in the diagnosis's own terms (GapDiagnosis), so that JSON, text,
// GUI and replay show it the same way.
//
//   gap        the output-error fit's lack of fit (χ²/ν beyond its limit, or
//              the band test) or a significant effect;
//   effects    every scanned effect: value ± σ, Δχ², alias (its Jacobian
//              column inside the constants' span), significant (Δχ² beyond
//              OeOptions::effect_significance·max(1, χ²/ν) at a physical value);
//   twins      significant effects whose χ² with them differs by less than
//              max(4, 1 %) from the verdict's: this capture cannot tell them;
//   verdict    the first significant effect (largest Δχ² first) that explains
//              the capture (no lack of fit left with it; without held-out data
//              nothing less is a verdict) and passes the held-out check below;
//              "none" without a gap; else "unexplained" (with the band where the
//              residual stands out and the closest effect, not named as cause).
//   held-out   another capture of the same transducer (any drive, one shot
//              included): its v2 predicted from its own v1 by the fit's model
//              without and with each candidate (predict_output_error, the fit's
//              covariance counted); shrink = 1 − g_after/g_before of the excess
//              g = √max(0, χ²/ν − 1). Where the held-out capture shows a gap,
//              the verdict's effect must shrink it by OeHeldout::min_shrink; an
//              effect that leaves a lack of fit in the fit, or one seen in the
//              fit below its significance (Δχ² ≥ 9), only by dominant_shrink.
//              Where it shows none, the effect must not create one. An effect
//              that fails is said not to carry over.
// Not yet: the regions of the impedance-domain diagnosis, more than one effect
// at a time.
#include <string>

#include "model/modal.hpp"
#include "update/gap_diagnosis.hpp"
#include "update/output_error.hpp"

namespace piezo::update {

// `r` from fit_output_error with scan_effects set. `fit_description` names the data.
GapDiagnosis gap_from_output_error(const OeResult& r, const std::string& fit_description);

// Shots that disagree (issue 33; OeShotConsistency): the verdict becomes
// "non_stationary" with the consistency's summary, no effect is named, and
// the finding leads d.disturbances. Both diagnosis paths (the output-error
// one and the impedance-domain one on the update's fit) call it. Returns
// whether it applied.
bool mark_non_stationary(GapDiagnosis& d, const OeShotConsistency& sc);

// The same, checked on held-out data: `heldout` another capture (its own R1
// and noise), predicted by the fit's model with the solver and class of the
// fit. Throws std::invalid_argument for unusable held-out data.
struct OeHeldout {
  OeData data;
  std::string description;
  double min_shrink = 0.3;  // the verdict's effect must shrink a held-out gap this much
  // … and this much when it leaves a lack of fit in the fit (then the verdict
  // says "not alone, or not exactly in the catalogue's form").
  double dominant_shrink = 0.7;
};
GapDiagnosis gap_from_output_error(const OeResult& r, const std::string& fit_description,
                                   model::ModalSolver& solver, const MaterialClass& cls, const OeHeldout& heldout,
                                   const OeOptions& options);

}  // namespace piezo::update
