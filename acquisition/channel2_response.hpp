#pragma once
// The simulated bench's generic DAQ stage: a channel-2 effect of the
// catalogue (model/effects.hpp, EffectStage::channel2) that the bench has no
// element of its own for (EffectInfo::simulated_natively false) is applied to
// the v2 record as its catalogue term, the same function the model
// (model/bench_response.hpp) multiplies the transfer by:
//   V2'(ω) = V2(ω)·Π term(value, ω).
// So an effect added to the catalogue alone is simulated and diagnosed alike.
#include <complex>
#include <functional>
#include <span>

#include "model/effects.hpp"

namespace piezo::acq {

using Channel2Response = std::function<std::complex<double>(double omega)>;

// The product of the terms of fx's channel-2 effects without a native
// element; empty if there are none (or all are at their neutral value).
Channel2Response channel2_response(const model::EffectSet& fx);

// v (uniformly sampled at dt) filtered by h: the record zero-padded to twice
// its length, so a causal response's tail runs into the padding and not back
// into the record's start. h(−ω) must be conj(h(ω)) (a real filter): only
// ω ≥ 0 is evaluated.
void apply_channel2_response(std::span<double> v, double dt, const Channel2Response& h);

}  // namespace piezo::acq
