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
//   verdict    the most significant effect when it explains the capture (no
//              lack of fit left with it; without held-out data nothing less
//              is a verdict), "none" without a gap, else "unexplained" (with
//              the band where the residual stands out and the closest effect,
//              which is not named as the cause).
// Not yet: held-out data (predicting another capture's v2 from its v1), the
// regions and curves of the impedance-domain diagnosis (empty here), more
// than one effect at a time.
#include <string>

#include "update/gap_diagnosis.hpp"
#include "update/output_error.hpp"

namespace piezo::update {

// `r` from fit_output_error with scan_effects set. `fit_description` names the data.
GapDiagnosis gap_from_output_error(const OeResult& r, const std::string& fit_description);

}  // namespace piezo::update
