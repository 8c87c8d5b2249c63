#pragma once
// JSON and text form of the per-mode figures (dsp/mode_figures.hpp) that
// `piezobench impedance` adds: key "modes" (one object per mode, every field
// with its unit in its name, σ beside it) and "mode_summary" (C^T, tan δ, the
// reference frequency, the hoop mode's frequency constant, notes). Fields are
// added, none renamed; NaN prints as null.
//   modes[{fs_hz, fs_sigma_hz, fp_hz, fp_sigma_hz, fm_hz, fm_sigma_hz, fn_hz, fn_sigma_hz,
//          k_eff, k_eff_sigma, k_eff2, k_eff2_sigma, qm_branch, qm_branch_sigma,
//          qm_bandwidth, qm_bandwidth_sigma, f1_hz, f2_hz, fs_conductance_hz,
//          r1_ohm, r1_sigma_ohm, l1_h, l1_sigma_h, c1_f, c1_sigma_f, c0_f, c0_sigma_f,
//          frequency_constant_hz_m, frequency_constant_sigma_hz_m,
//          fit{points, window_lo_hz, window_hi_hz, converged, weighted, chi2_per_dof,
//              rms_rel_residual, iterations}, notes[]}]
//   mode_summary{free_capacitance_f, free_capacitance_sigma_f, tan_delta, tan_delta_sigma,
//                reference_hz, hoop_mode, mean_diameter_m, mean_diameter_source,
//                frequency_constant_hz_m, frequency_constant_sigma_hz_m, sweeps, notes[],
//                source (what the figures are of: the updated FE model or a BVD fit per mode)}
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>

#include "dsp/mode_figures.hpp"

namespace piezo::jobs {

nlohmann::json modes_json(const dsp::ModeFiguresResult& r);
nlohmann::json mode_summary_json(const dsp::ModeFiguresResult& r, double mean_diameter_m,
                                 const std::string& mean_diameter_source);
// The per-mode table (from the JSON above) as text.
void print_mode_figures(std::FILE* out, const nlohmann::json& modes, const nlohmann::json& summary);

}  // namespace piezo::jobs
