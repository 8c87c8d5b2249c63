#pragma once
// The per-mode figures (dsp/mode_figures.hpp) of a capture's impedance
// estimate: D_mean from the capture's geometry (or the project's default tube,
// said so), the estimator's σ per point when it has one. One implementation for
// `piezobench impedance` and the pipeline ("Measure and update", replay), whose
// records then carry "modes" and "mode_summary" (jobs/json/mode_figures_json.hpp) for
// limits on fs, k_eff, Qm, C^T and tan δ (jobs/report/limits.hpp).
#include <string>

#include "acquisition/capture.hpp"
#include "dsp/impedance_types.hpp"
#include "dsp/mode_figures.hpp"

namespace piezo::jobs {

struct CaptureModeFigures {
  dsp::ModeFiguresResult figures;
  double mean_diameter_m = 0;
  std::string
      mean_diameter_source;  // "capture /setup" | "the project's default tube (not in the capture)"
  std::string error;         // non-empty: no figures (e.g. a grid too short), and why
};

CaptureModeFigures capture_mode_figures(const acq::Capture& cap, const dsp::ImpedanceResult& z);

}  // namespace piezo::jobs
