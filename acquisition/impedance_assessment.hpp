#pragma once
// A trustworthy impedance from a capture: the estimate of its "dut" shots
// with everything that makes a number trustworthy around it —
//   fixture compensation and channel deskew from the capture's calibration
//   shots (capture_calibration.hpp), with a statement of the fixture model;
//   per-frequency uncertainty band for |Z| and phase (dsp/uncertainty.hpp):
//   bootstrap over shots, or noise propagation, plus the standards' part;
//   a Kramers–Kronig / passivity check of the result (dsp/kramers_kronig.hpp);
//   per-shot validity flags: clipping, coherence, Prony reconstruction (dsp/validity.hpp);
//   the Prony stabilization chart (dsp/stabilization.hpp).
// The function the impedance command and the pipeline call.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "acquisition/capture.hpp"
#include "acquisition/capture_calibration.hpp"
#include "dsp/divider_baseline.hpp"
#include "dsp/cross_spectra.hpp"
#include "dsp/fft_ratio.hpp"
#include "dsp/kramers_kronig.hpp"
#include "dsp/prony_impedance.hpp"
#include "dsp/stabilization.hpp"
#include "dsp/stepped_sine.hpp"
#include "dsp/uncertainty.hpp"
#include "dsp/validity.hpp"

namespace piezo::acq {

enum class UncertaintySource { Auto, Shots, Noise, None };

// Prony-SS as the bench records: the drive ramps from idle at −Δt onto its
// first sample (the AWG), and the samples before the first decimated one enter
// the transforms as recorded (the fast transient of the tube's modes above the
// band, which an order set by the noise leaves out: 4.9 % / 3.2° next to the
// 82 kHz resonance without it, see docs/dsp-methods.md "Measured").
inline dsp::PronyImpedanceOptions bench_prony_options() {
  dsp::PronyImpedanceOptions o;
  o.ramp_onset = true;
  o.direct_samples = dsp::PronyImpedanceOptions::kDirectFilterLength;
  return o;
}

// The one estimate (issue 41 item 4): the band, grid and record length the
// pipeline's estimate stage uses (jobs/pipeline/estimate_stage.cpp), and
// `piezobench impedance` / `figures` by default, so that the three report the
// same features of the same capture. The band reaches the tube's third
// short/open-circuit pair with room (the model's mode range,
// jobs/seed_features.hpp) and never past fs/4; Prony fits at most
// kDefaultEstimateSamples samples after t = 0 (its Hankel SVD grows as the
// square; the transient has decayed into the noise long before on the bench).
inline constexpr double kDefaultEstimateBandHz = 120e3;
inline constexpr double kDefaultEstimateStepHz = 100.0;
inline constexpr std::size_t kDefaultEstimateSamples = 6000;
struct EstimateDefaults {
  double fmin_hz = 0, fmax_hz = 0, step_hz = 0;
  std::size_t max_samples = 0;  // samples after t = 0 Prony fits
};
// Of the first transient dut shot (sample rate and record length).
EstimateDefaults default_estimate(const Shot& first);

struct AssessmentOptions {
  std::string method = "prony";     // a transient estimator's key (acquisition/estimators/): prony | fft | xspec
  std::optional<std::size_t> shot;  // one shot (capture index); empty: every transient dut shot
                                    // of the first one's drive, averaged (xspec: as segments)
  double fmin_hz = 0.0, fmax_hz = 0.0,
         step_hz = 0.0;  // 0: step fmax/2000, fmin one step, fmax fs/4
  // band_hz and features.fmin_hz are filled from the grid.
  dsp::PronyImpedanceOptions prony = bench_prony_options();
  dsp::FftRatioOptions fft;        // fmin/fmax filled from the band
  dsp::CrossSpectraOptions xspec;  // fmin/fmax filled from the band
  dsp::SteppedSineOptions sine;    // features' fmin/fmax filled from the band (jobs/impedance_job.cpp)

  // A real bench's slow disturbances (issue 33): each shot's channel-1-minus-
  // channel-2 baseline (slow wander, mains hum) tested (dsp/divider_baseline.hpp)
  // and reported; removed from channel 1 before the estimate only with
  // `baseline_remove` (on our bench the removal's own noise in the lowest bins
  // cost as much as the baseline did: docs/dsp-methods.md).
  bool baseline = true;
  bool baseline_remove = false;
  dsp::DividerBaselineOptions baseline_options;

  bool compensate = true;                  // use the capture's calibration shots, when it has any
  std::optional<dsp::FixtureModel> model;  // empty: the most complete the standards allow
  int standard_degree = 4;
  bool deskew = true;
  std::optional<double> skew_s;  // a stored skew, applied when the capture has no calibration shot

  UncertaintySource uncertainty =
      UncertaintySource::Auto;  // Auto: Shots with >= 3 shots, else Noise
  std::size_t bootstrap = 30;   // replicates of the bootstrap over shots
  std::uint64_t seed = 11;
  double coverage_factor = 1.96;
  // Prony: the model-order part of the band, from the estimates at the orders
  // p ± order_spread_step around the chosen p (σ = the larger deviation from it).
  bool order_spread = true;
  std::size_t order_spread_step = 2;

  bool kk = true;
  dsp::KramersKronigOptions kk_options;
  bool validity = true;
  dsp::ShotValidityOptions validity_options;
  bool stabilization = true;  // prony only
  dsp::StabilizationOptions stabilization_options;
};

struct ImpedanceAssessment {
  dsp::ImpedanceResult result;         // deskewed and compensated: the one to use
  dsp::ImpedanceResult uncompensated;  // the same estimator on the records as recorded
  std::optional<CaptureCalibration> calibration;
  dsp::FixtureModel model = dsp::FixtureModel::None;
  std::string model_description;  // which model of the fixture the result assumes
  double skew_applied_s = 0.0;
  std::string skew_source;  // where the skew came from ("" when none)
  std::optional<dsp::ImpedanceBand> band;
  std::optional<dsp::KramersKronigResult> kk;
  std::optional<dsp::ValidityReport> validity;  // one entry per shot in `shots`
  std::optional<dsp::StabilizationChart> stabilization;
  std::vector<std::string> shots;  // dut shots used
  std::vector<dsp::DividerBaseline> baselines;  // per shot in `shots` (AssessmentOptions::baseline)
  bool baseline_removed = false;                // the found ones were removed (AssessmentOptions::baseline_remove)
  std::vector<std::string> notes;  // what was skipped and why
};

// Throws std::invalid_argument (naming the shot, the option or the problem)
// for a capture without usable dut shots, a bad method or band, unusable
// calibration shots. The estimate is the estimator registry's entry of
// `method` (acquisition/estimators/estimator.hpp), one that takes transient shots.
ImpedanceAssessment assess_impedance(const Capture& cap, const AssessmentOptions& opt);

}  // namespace piezo::acq
