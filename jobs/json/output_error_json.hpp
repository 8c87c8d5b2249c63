#pragma once
// JSON form of an output-error fit (update/output_error.hpp), the same in
// `piezobench update CAP.h5 --json` (methods.oe) and in the pipeline's report
// (replay records, GUI/demo JSON: "output_error"):
//   {method:"oe", converged, status, message, updated{YE11,nu12,d31,epsT33_rel},
//    parameters[{name, unit, value, sigma, relative_sigma, nominal,
//                sigma_statistical, status, reason, note}],
//    correlation{names[], matrix[][]}, corr_nu12_d31,
//    damping{rayleigh_alpha, rayleigh_beta},
//    fit{excitation, shots, band_hz, residual_samples, noise_source, noise_rms_v,
//        residual_rms_v, chi2_per_dof, chi2_limit, lack_of_fit, noise_dof,
//        starts, iterations, evaluations, optima[{…constants, chi2}]}, seconds}
#include <nlohmann/json.hpp>
#include <string>

#include "update/output_error.hpp"

namespace piezo::jobs {

nlohmann::json tube_params_json(const update::TubeParams& p);
nlohmann::json output_error_json(const update::OeResult& r, const std::string& excitation);
// The slow disturbances found (issue 33): OeResult/OePrediction::baseline.
nlohmann::json baseline_json(const update::OeBaseline& b);
// The shots' agreement before pooling (issue 33): OeResult::shot_consistency.
nlohmann::json shot_consistency_json(const update::OeShotConsistency& c);

}  // namespace piezo::jobs
