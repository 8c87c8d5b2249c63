#pragma once
// The jobs' room (jobs/): the bench effects a simulated bench adds and the
// model lacks (model/effects.hpp), from the text an operator types —
// "series_resistance=15, channel_skew=1e-7". The GUI's instrument panel
// uses it; the CLI takes one NAME=VALUE per --effect.
#include <string>

#include "model/effects.hpp"

namespace piezo::jobs {

// Comma-separated NAME=VALUE items, blanks around each ignored; throws
// std::invalid_argument naming the bad item.
model::EffectSet parse_sim_effects(const std::string& text);

}  // namespace piezo::jobs
