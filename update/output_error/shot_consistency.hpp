#pragma once
// The shots' consistency before pooling (issue 33 item 2;
// update/output_error.hpp, OeShotConsistency): each averaged shot's constants
// linearised about the pooled answer, their homogeneity, and per constant the
// better of a drift and a step. Internal to update/output_error/.
#include <vector>

#include "update/output_error.hpp"
#include "update/output_error/fitter.hpp"
#include "update/output_error/forward_model.hpp"
#include "update/output_error/noise.hpp"
#include "update/output_error/shot_average.hpp"

namespace piezo::update::oe {

// `sigma`: the noise the answer's Jacobian is weighted by; `nu12_scale`: the
// nominal's nu12 over the answer's (nu12's coordinate is relative to the
// nominal). Not tested (tested = false) with fewer than two shots, without
// the answer's Jacobian or a measurable noise per shot.
OeShotConsistency shot_consistency(const FitAnswer& answer, Problem& prob, const OffsetWhitening& whiten,
                                   const Averaged& rec, double sigma, double nu12_scale,
                                   const std::vector<OeParameter>& parameters);

}  // namespace piezo::update::oe
