#pragma once
// The jobs' room (jobs/): the seed's chain on a capture (issue 40) — the
// features extended CMCM and least squares use, taken from an impedance
// estimate (`piezobench update CAP.h5 --method cmcm|lm`: the same estimate as
// `piezobench impedance CAP.h5`; the pipeline: its estimate stage's), kept only
// inside the band the drive covers (dsp/drive_band.hpp) and the model's mode
// range, each with its σ; then update::update_from_features and its JSON.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "acquisition/capture.hpp"
#include "dsp/drive_band.hpp"
#include "dsp/impedance_types.hpp"
#include "jobs/pipeline/capture_fit.hpp"
#include "update/feature_update.hpp"

namespace piezo::jobs {

// Channel 1 of the capture's transient dut shots of the first one's drive
// (averaged when repeated; only those named in `shots` when it is not empty:
// the shots an estimate used), its band. Throws std::invalid_argument without such a shot.
dsp::DriveBand capture_drive_band(const acq::Capture& cap, const std::vector<std::string>& shots = {});

// The estimator's model-order part of the features' σ (issue 40): Prony's
// parametric bootstrap holds the noise at its chosen order p only; a mode the
// order leaves out moves the others and the low-frequency capacitance (refsim
// case 03 at order 4: C 0.43 % low, 3.6 bootstrap σ). Each feature's σ is
// widened in quadrature by how far it moves at the orders in `others` (p ± 2,
// as the impedance command's uncertainty band does for Z): the nearest feature
// of the same kind within 3 %; the capacitance always.
void widen_by_order_spread(dsp::ImpedanceFeatures& f, const std::vector<dsp::ImpedanceFeatures>& others);

struct SeedFeatures {
  update::MeasuredFeatures features;  // in the band, with σ; possibly no resonance at all
  update::FeatureBand band;           // the drive's band ∩ the model's mode range (∩ the estimate's)
  dsp::DriveBand drive;
  double model_lo_hz = 0, model_hi_hz = 0;
  std::string no_features;  // why no resonance / anti-resonance was kept ("" when some were)
  nlohmann::json json;      // what was kept and what dropped, and why
};

// The model's mode range: within a factor `kModelRange` in frequency of the
// nominal model's first and third electrically active short- and
// open-circuit modes (YE11 within a factor 2.25 of the nominal). At most three
// of each kind are kept (the modes the model pairs them with, §6.4.1), and
// the capacitance at the seed's f_L = 400 Hz (Tables 4/5).
inline constexpr double kModelRange = 1.5;
SeedFeatures select_seed_features(const dsp::ImpedanceFeatures& z, double estimate_hi_hz,
                                  const dsp::DriveBand& drive, const CaptureModel& cm);

// The method's JSON: method, converged, status, message (the reason), updated,
// parameters[] (name, unit, value, sigma, sigma_statistical, relative_sigma,
// status, reason, note, as the output-error fit's), features, residuals, chi2.
nlohmann::json feature_update_json(const update::FeatureUpdate& u, const SeedFeatures& sf);

}  // namespace piezo::jobs
