#pragma once
// JSON form of an impedance assessment (acquisition/impedance_assessment.hpp):
// the fields `piezobench impedance --json` adds to its output, for the CLI,
// the GUI's JSON report and anyone replaying captures headless.
//   compensation  {applied, model, description, fixture{…measured quantities…},
//                  standards{open|short|load{shots, chi2_reduced, residual_rel_rms}},
//                  load_ohm, load_parallel_f, notes[]}
//   deskew        {applied, skew_s, skew_ns, source}
//   uncompensated {re_ohm[], im_ohm[]}      (the estimator on the records as recorded)
//   uncertainty   {source, coverage_factor, abs_ohm[], abs_sigma_ohm[], phase_deg[],
//   phase_sigma_deg[]} kramers_kronig{pass, causal, passive, threshold, rms_residual, max_residual,
//   max_residual_f_hz,
//                  max_passivity, residual[], note}
//   validity      {shots[{name, clipped, coherence, reconstruction_ratio, flags[]}],
//                  low_coherence_fraction, coherence_f_hz[], coherence[]}
//   stabilization {orders[], selected_order, poles[{order, freq_hz, damping_ratio, stability}]}
//   notes[]
#include <nlohmann/json.hpp>

#include "acquisition/impedance_assessment.hpp"

namespace piezo::jobs {

nlohmann::json fixture_json(const dsp::FixtureCalibration& f);
nlohmann::json assessment_json(const acq::ImpedanceAssessment& a);

}  // namespace piezo::jobs
