#pragma once
// The jobs' room (jobs/): `piezobench figures` — per-mode figures an engineer
// can trust (issue 34), from an impedance analyzer's or VNA's file (any
// format of dsp/impedance_files): the multi-mode equivalent circuit of
// dsp/equivalent_circuit fitted to complex Z, each figure with its σ (lack of
// fit included); or from a capture, by default (--method oe) on the estimator
// the capture supports best: the output-error fit of the FE model to the
// samples (jobs/pipeline/capture_fit.hpp), the figures those of the updated
// model's short- and open-circuit modes with σ from the constants' covariance
// (update/model_figures.hpp), within the fit's band; --method fft|xspec|prony
// fits the circuit to that impedance estimate instead. The capture's FFT ratio
// is the data shown beside the model. ui/cli/cmd_figures.cpp parses the
// options and prints.
#include <Eigen/Core>
#include <filesystem>
#include <iosfwd>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "acquisition/estimators/estimator.hpp"
#include "dsp/equivalent_circuit.hpp"


namespace piezo::jobs {

// The impedance estimators `--method` takes for a capture besides oe: those of
// the registry that take a transient (acq::builtin_estimators()), in its order.
std::vector<std::string> figures_estimators();

struct FiguresRequest {
  std::string file;
  int max_modes = 12;         // branches at most
  double band_lo_hz = 0;      // 0: the data's
  double band_hi_hz = 0;      // 0: the data's (a capture: the estimate's band)
  std::string method;         // a capture's estimator: oe, fft, xspec, prony ("": oe; a file: none)
  std::string material;       // oe: the nominal material (empty: the capture's own)
  std::string columns;        // a table file's column names ("f[kHz],G[uS],B[uS]"; empty: its header)
};

struct FiguresJobResult {
  std::string source;     // "file", "capture"
  std::string format;     // the file's format, or the capture's estimator
  std::string quantity;   // what the numbers were
  Eigen::VectorXd f_hz;
  Eigen::VectorXcd z_ohm;
  Eigen::VectorXd z_sigma_ohm;  // per point sqrt(E|δZ|²); empty when the data carry none
  dsp::CircuitFit fit;
  std::vector<std::string> notes;  // the reader's and the job's
  // --method oe: the output-error fit the figures come from (its JSON, as
  // `update --json`'s methods.oe) and the FE port models the σ cost.
  nlohmann::json output_error;
  bool model_figures = false;
  std::vector<std::string> warnings;  // the fit's (lack of fit, constants not identifiable)
};

// Throws InputError (jobs/job_error.hpp) for a file that is neither a capture
// nor a readable impedance file, or a band with fewer than 8 points.
FiguresJobResult run_figures(const FiguresRequest& req);

nlohmann::json figures_json(const FiguresRequest& req, const FiguresJobResult& r);
// One row per mode: mode, fs_hz, fs_sigma_hz, fp_hz, ... (value and σ columns).
void write_figures_csv(std::ostream& os, const FiguresJobResult& r);
// |Z| and phase of the data and the fitted network, fs/fp markers; PNG.
void write_figures_plot(const FiguresJobResult& r, const std::filesystem::path& png);

}  // namespace piezo::jobs
