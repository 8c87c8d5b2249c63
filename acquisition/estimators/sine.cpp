// Estimator entry "sine" (estimator.hpp): stepped sine, a lock-in
// (three-parameter sine fit, dsp/stepped_sine.hpp) per shot and frequency.
#include <stdexcept>

#include "acquisition/estimators/estimator.hpp"
#include "dsp/stepped_sine.hpp"

namespace piezo::acq {

EstimatorEntry sine_estimator() {
  auto lock_in = [](const EstimateInput& in) {
    if (in.frequencies_hz.size() != in.records.size())
      throw std::invalid_argument("sine estimator: one drive frequency per record expected");
    std::vector<dsp::SineShot> shots;
    for (std::size_t k = 0; k < in.records.size(); ++k) shots.push_back({in.records[k], in.frequencies_hz[k]});
    dsp::SteppedSineOptions o = in.options.sine;
    o.features.fmin_hz = in.band.fmin_hz;
    if (in.band.fmax_hz > 0) o.features.fmax_hz = in.band.fmax_hz;
    return dsp::impedance_stepped_sine(shots, o);
  };
  return {"sine", "stepped sine", "stepped sine: a lock-in (three-parameter sine fit) per shot, one frequency each",
          {.sine_shots = true, .sigma_per_point = true}, "lock-in fit covariance", lock_in};
}

}  // namespace piezo::acq
