#pragma once
// The per-mode figures (dsp/mode_figures.hpp's form) of a capture — one
// implementation for `piezobench impedance` and the pipeline ("Measure and
// update", replay), whose records then carry "modes" and "mode_summary"
// (jobs/json/mode_figures_json.hpp) for limits on fs, k_eff, Qm, C^T and tan δ
// (jobs/report/limits.hpp), the lot report and the GUI's Modes view. Two
// sources:
//  - capture_mode_figures: a BVD fit per mode to an impedance estimate, σ from
//    the estimator's per-point σ (`impedance --figures`; the pipeline's
//    fallback when the output-error fit did not converge);
//  - model_mode_figures (issue 34): the output-error fit's updated FE model —
//    the estimator a capture supports best — its short- and open-circuit modes
//    within the fit's band, σ from the constants' covariance
//    (update/model_figures.hpp); C^T the model's at 1 kHz (the fit's baseline
//    model keeps a bench's slow disturbances out of it, the estimate's lowest
//    bins do not); tan δ stays the estimate's (`measured`): the five-parameter
//    model has no dielectric loss to give it.
// D_mean from the capture's geometry (or the project's default tube, said so).
#include <string>

#include "acquisition/capture.hpp"
#include "dsp/impedance_types.hpp"
#include "dsp/mode_figures.hpp"
#include "jobs/pipeline/capture_fit.hpp"
#include "update/output_error.hpp"

namespace piezo::jobs {

struct CaptureModeFigures {
  dsp::ModeFiguresResult figures;
  double mean_diameter_m = 0;
  std::string
      mean_diameter_source;  // "capture /setup" | "the project's default tube (not in the capture)"
  std::string source;        // what the figures are of (JSON mode_summary.source)
  std::string error;         // non-empty: no figures (e.g. a grid too short), and why
};

CaptureModeFigures capture_mode_figures(const acq::Capture& cap, const dsp::ImpedanceResult& z);

// `measured`: the estimate's figures (tan δ kept from them), or null.
// Never throws: a failure is `error`.
CaptureModeFigures model_mode_figures(const acq::Capture& cap, const CaptureModel& cm, const update::OeResult& r,
                                      const CaptureModeFigures* measured);

}  // namespace piezo::jobs
