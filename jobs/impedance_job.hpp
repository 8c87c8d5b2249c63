#pragma once
// The jobs' room (jobs/): `piezobench impedance` — the impedance of a
// capture's "dut" shots by one of the dsp/ estimators (Prony-SS, FFT ratio,
// cross spectra through acq::assess_impedance with its fixture compensation,
// deskew, uncertainty band, Kramers-Kronig check, shot validity and
// stabilization chart; stepped sine compensated here), its JSON (features,
// Prony order and singular values, trust, per-mode figures), CSV and
// Touchstone forms. ui/cli/cmd_impedance.cpp parses the options and prints.
// The estimators and their keys: acq::builtin_estimators()
// (acquisition/estimators/estimator.hpp), which the front ends read for their
// choices and help.
#include <cstddef>
#include <iosfwd>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "acquisition/capture.hpp"
#include "acquisition/estimators/estimator.hpp"
#include "acquisition/impedance_assessment.hpp"
#include "dsp/drive_band.hpp"
#include "dsp/impedance_types.hpp"

namespace piezo::jobs {

struct ImpedanceRequest {
  std::string file, method = "prony", window = "rect";  // method: an estimator's key
  std::optional<std::size_t> shot, samples, order, segment;
  // 0 / unset: the one estimate's (acq::default_estimate: the pipeline's band,
  // grid and Prony record length).
  double fmin = 0, fmax = 0, step = 0, overlap = 0.5;
  std::size_t bootstrap = 20;
  // Trust (issue 10): compensation, deskew, uncertainty, validity, KK, stabilization.
  std::string compensation = "auto", uncertainty = "auto", stabilization = "2:30:2";
  std::optional<double> skew_ns;
  // prony/fft: every transient dut shot of the drive averaged (the pipeline's
  // estimate, issue 41 item 4) unless one_shot or a shot is named.
  bool no_deskew = false, average = true, one_shot = false, no_kk = false, no_validity = false, no_stabilization = false;
  bool no_baseline = false;      // do not test for a bench's slow disturbances (issue 33)
  bool remove_baseline = false;  // remove a significant one from channel 1 before the estimate
  std::size_t bootstrap_shots = 30;
};

struct ImpedanceJobResult {
  acq::Capture capture;
  dsp::ImpedanceResult z;
  std::vector<std::string> shots;  // the names of the shots estimated
  acq::AssessmentOptions trust;    // as the request stated them
  std::optional<acq::ImpedanceAssessment> assessed;  // prony, fft, xspec
  std::optional<dsp::ImpedanceBand> band;
  std::optional<acq::CaptureCalibration> sine_cal;  // stepped sine: compensated here, not by assess_impedance
  double band_hz = 0;                               // upper edge of the estimate's band (0: not stated)
  // The band the recorded drive covers (transient methods; dsp/drive_band.hpp):
  // a feature outside it was estimated from noise and is not significant.
  std::optional<dsp::DriveBand> drive;
};

// Throws InputError (jobs/job_error.hpp) for a request the capture cannot
// serve, acq::CaptureError for a bad capture.
ImpedanceJobResult run_impedance(const ImpedanceRequest& req);

// The result document: file, shots, method, features, Prony's poles and
// Rayleigh fit, Z and its sigma; then the trust fields (compensation, deskew,
// notes, uncertainty, validity, Kramers-Kronig, stabilization).
nlohmann::json impedance_json(const ImpedanceRequest& req, const ImpedanceJobResult& r);
// Adds "modes" and "mode_summary" (jobs/json/mode_figures_json.hpp).
void add_impedance_mode_figures(nlohmann::json& j, const ImpedanceJobResult& r);
// f_hz,re_ohm,im_ohm (then the uncertainty band's columns when there is one).
void write_impedance_csv(std::ostream& os, const ImpedanceJobResult& r);
// Touchstone 1-port (Z, RI, normalised to 50 ohm).
void write_impedance_s1p(std::ostream& os, const ImpedanceJobResult& r);

}  // namespace piezo::jobs
