// Estimator entry "xspec" (estimator.hpp): Welch cross spectra
// (dsp/cross_spectra.hpp) over the drive's shots as segments, with coherence.
#include "acquisition/estimators/estimator.hpp"
#include "dsp/cross_spectra.hpp"

namespace piezo::acq {

EstimatorEntry xspec_estimator() {
  return {"xspec", "cross-spectra",  // the pipeline's curve "measured (cross-spectra)"
          "Welch auto and cross spectra over the shots as segments (H1, H2), with the coherence",
          {.transient_shots = true, .segments = true, .sigma_per_point = true}, "noise propagation",
          [](const EstimateInput& in) {
            dsp::CrossSpectraOptions o = in.options.xspec;
            o.fmin_hz = in.band.fmin_hz;
            o.fmax_hz = in.band.fmax_hz;
            return dsp::impedance_xspec(in.records, o);
          }};
}

}  // namespace piezo::acq
