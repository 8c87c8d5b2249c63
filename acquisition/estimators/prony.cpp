// Estimator entry "prony" (estimator.hpp): Laplace-domain Prony-SS
// (dsp/prony_impedance.hpp) on the sample-by-sample mean of the drive's shots.
#include "acquisition/estimators/estimator.hpp"
#include "dsp/prony_impedance.hpp"

namespace piezo::acq {

EstimatorEntry prony_estimator() {
  auto prony = [](const EstimateInput& in) {
    const OwnedRecord avg = mean_record(in.records);
    dsp::PronyImpedanceOptions o = in.options.prony;
    o.prony.band_hz = in.band.fmax_hz;
    o.features.fmin_hz = in.band.fmin_hz;
    if (in.order) o.prony.order = in.order;
    if (in.bootstrap) o.bootstrap = *in.bootstrap;
    return dsp::impedance_prony(avg.view(), dsp::make_grid(in.band.fmin_hz, in.band.fmax_hz, in.band.step_hz), o);
  };
  return {"prony", "Prony-SS",  // the pipeline's curve "measured (Prony-SS)"
          "Laplace-domain Prony-SS of the averaged transient: Z(s) from poles and residues, features from its zeros",
          {.transient_shots = true, .averages_shots = true, .sigma_per_point = true, .modes = true},
          "Prony parametric bootstrap", prony};
}

}  // namespace piezo::acq
