#pragma once
// The catalogue's effects (model/effects.hpp, OeOptions::scan_effects) fitted
// one at a time as a sixth coordinate beside the five, from the fit's optimum
// (issue 18): each effect's alias against the constants, its first-order
// score, and an LM run where the score may be significant; under a lack of
// fit the two most significant get the coarse grid again. Internal to
// update/output_error/.
#include "update/output_error.hpp"
#include "update/output_error/fitter.hpp"
#include "update/output_error/forward_model.hpp"

namespace piezo::update::oe {

// out.effects, largest Δχ² first (each task on up to two threads, its answer
// independent of the thread and the order). After identify (sigma.hpp):
// reads out's χ²/ν and limit, answer, covariance_rel, band test and lack of
// fit. Throws std::invalid_argument for a name not in the catalogue. Returns
// the FE models the forks built (fitter.prob counts its own).
int scan_effects(const FitAnswer& answer, Fitter& fitter, const Coordinates5& co,
                 const TubeParams& nominal, const OeOptions& opt, OeResult& out);

}  // namespace piezo::update::oe
