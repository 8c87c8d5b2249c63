#pragma once
// The output-error fit refitted WITH an effect the gap diagnosis named
// (issue 41 item 2): the result a technician signs is the corrected model,
// not the fit that lacked the effect. One OeResult as the fit's own, so that
// everything downstream (parameter rows, per-mode figures, JSON) reads it the
// same way.
//
// Sigmas: the statistical part from the covariance of the fit with the
// effect (OeEffect::covariance_rel, Birge-widened by its own χ²/ν), the
// measurement chain's type-B part (R1, Cp, gain, skew tolerances) taken over
// from the fit without it — the chain's tolerances do not change when an
// effect is added — and the two added in quadrature.
// Status: "ok" only where the fit with the effect explains the capture
// (OeEffect::explains) and the relative sigma is within the limit
// (OeOptions::identifiable_rel_sigma; 50 % for the loss).
#include <optional>
#include <string>

#include "update/output_error.hpp"

namespace piezo::update {

// Null when `r` scanned no effect named `effect`, or its refit has no finite value.
std::optional<OeResult> corrected_result(const OeResult& r, const std::string& effect,
                                         double identifiable_rel_sigma = OeOptions{}.identifiable_rel_sigma);

}  // namespace piezo::update
