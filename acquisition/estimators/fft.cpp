// Estimator entry "fft" (estimator.hpp): the direct FFT ratio
// (dsp/fft_ratio.hpp) of the sample-by-sample mean of the drive's shots.
#include "acquisition/estimators/estimator.hpp"
#include "dsp/fft_ratio.hpp"

namespace piezo::acq {

EstimatorEntry fft_estimator() {
  auto fft = [](const EstimateInput& in) {
    dsp::FftRatioOptions o = in.options.fft;
    o.fmin_hz = in.band.fmin_hz;
    o.fmax_hz = in.band.fmax_hz;
    return dsp::impedance_fft(mean_record(in.records).view(), o);
  };
  return {"fft", "FFT",  // the pipeline's curve "measured (FFT)"
          "direct FFT ratio of the averaged transient, with a window of choice; model-free",
          {.transient_shots = true, .averages_shots = true, .sigma_per_point = true}, "noise propagation", fft};
}

}  // namespace piezo::acq
