#pragma once
// "Measure and update", end to end: acquire (or replay a capture) → estimate
// Z(ω) → update the FE model → diagnose the remaining gap. One implementation
// serves the GUI's button, `piezobench demo` and headless replay. Stages that
// have not landed yet are reported as skipped, never faked. The pipeline's room (jobs/pipeline).
#include <atomic>
#include <complex>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "acquisition/calibration_plan.hpp"
#include "acquisition/plan.hpp"
#include "acquisition/sim_setup.hpp"
#include "dsp/fixture_calibration.hpp"
#include "jobs/pipeline/capture_mode_figures.hpp"
#include "jobs/pipeline/work.hpp"
#include "update/gap_diagnosis.hpp"
#include "update/output_error.hpp"

namespace piezo::jobs {

struct PipelineRequest {
  // Acquire with `plan` on `instrument` (sim | tcp://… | usbtmc://…), or replay `replay_capture`.
  std::string instrument = "sim";
  std::string daq;  // optional DAQ address
  acq::MeasurementPlan plan;
  acq::SimSpec sim;  // used when instrument == "sim"
  std::string capture_out = "capture.h5";
  // false: an existing capture_out is never overwritten — the capture goes to
  // NAME-2.h5, NAME-3.h5 … and a warning says where (the GUI's default; the
  // demo rewrites its own demo-out/ files).
  bool overwrite_capture = true;
  std::string replay_capture;  // non-empty: skip acquisition
  // Read replayed and held-out captures in a child process first
  // (acquisition/contained_read.hpp: a crash of libhdf5 on a damaged file
  // refuses the file instead of ending this process). Off where the caller is
  // itself a disposable worker process (jobs/replay).
  bool replay_contained = true;
  std::string material = "apc850";  // nominal model to update
  bool isotropic = true;
  // Gap diagnosis (update/gap_diagnosis.hpp). Held-out data, in this order:
  // `heldout_capture` (replay), a second acquisition with `heldout_plan`
  // (written next to capture_out as NAME-heldout.h5), dut shots of another
  // excitation in the capture, or else the odd-numbered repeated shots (the
  // fit then uses the even ones).
  bool diagnose = true;
  std::optional<acq::MeasurementPlan> heldout_plan;
  std::string heldout_capture;
  // An unreadable `heldout_capture` is a warning (the capture is diagnosed
  // without it) instead of the capture's failure: replay's pairing by name.
  bool heldout_optional = false;
  std::vector<std::string> gap_candidates;  // empty: all supported
  // Relative floor added in quadrature to the measured noise of ln Z (model
  // and estimator systematics that repeated shots cannot see).
  double gap_floor = 2e-3;
  // Fixture standards measured before the dut shots (simulator: switched by
  // SIM:DUT; real bench: `prompt` asks the technician).
  std::vector<acq::CalibrationStep> calibration;
  acq::TechnicianPrompt prompt;
  // Use the capture's calibration shots (fixture measured, see PipelineResult::fixture).
  bool use_calibration = true;
  // The seed's chain beside the output-error fit: the port-model refinement
  // of Prony's features and extended CMCM on them (LM where CMCM fails).
  // Off, the pipeline runs Prony-SS (plots, features) and the output-error
  // fit only: replay's default, for throughput (`replay --seed-chain` turns it on).
  bool seed_chain = true;
  // With seed_chain off, run the seed's chain anyway when the output-error fit
  // did not converge (on Prony's features as estimated): the update it can
  // still give, without paying for it on every capture (issue 43: 500-700 FE
  // modal solves of a `diagnose` went to a chain whose result was not used).
  bool seed_chain_fallback = true;
  // Also run least squares (LM) on the seed's features beside extended CMCM
  // (the demo's comparison table); otherwise LM runs only where CMCM fails.
  bool compare_lm = false;
  // The output-error fit's options: the measurement chain's stated
  // tolerances (`--r1-tolerance` …, ui/cli/cli_common.hpp) among them.
  update::OeOptions oe_options;
};

struct Curve {
  std::string label;
  std::vector<double> f_hz;
  std::vector<std::complex<double>> z_ohm;
  // A measured curve's estimator: its key in acq::builtin_estimators()
  // (acquisition/estimators/), which front ends style it by; "" for a model's.
  std::string estimator = {};
};

struct ParamRow {
  std::string name, unit;
  // `updated` is the pipeline's update (PipelineResult::update_method: the
  // output-error fit, or the seed's chain where that did not converge), with
  // its sigma and status when it has them.
  double original = 0, updated = 0;
  std::optional<double> sigma;
  std::string status;           // "ok" | "not identifiable" (output-error); "ok (seed's chain)" / "not identifiable (seed's chain)" with its sigma (issue 40)
  std::optional<double> truth;  // only when the bench is simulated (shown for the demo)
  // Side by side: the seed's extended CMCM (or its LM fallback) on the
  // features, least squares (LM) on the same features when asked for, and the
  // output-error fit of the capture (update/output_error.hpp) with sigma and status.
  std::optional<double> cmcm, lm;
  std::optional<double> oe, oe_sigma;
  std::string oe_status;
  // When the diagnosis named an effect (PipelineResult::corrected), `updated`,
  // `sigma` and `status` are the constants refitted WITH it (issue 41 item 2)
  // and these hold the update's own, without it.
  std::optional<double> uncorrected, uncorrected_sigma;
  std::string uncorrected_status;
};

// The constants refitted with the effect the gap diagnosis named: the result
// (ParamRow::updated) when there is one, labelled with the effect and its value.
struct CorrectedConstants {
  std::string effect, unit;
  double value = 0, sigma = 0;            // SI
  std::optional<double> heldout_shrink;   // of the held-out gap, 0..1 (none: not checked on held-out data)
  bool heldout_without_gap = false;       // the held-out data had no gap of their own
  std::string source;                     // "output-error" | "impedance" (the diagnosis' path)
  std::string label;                      // one line for the technician
};

struct StageReport {
  std::string name;
  bool ran = false;
  std::string note;  // what happened, or why it was skipped
};

struct PipelineResult {
  std::string capture_path;
  // The capture's own set-up as a plan (its /setup, its first transient dut
  // shot's drive, rate and length, its dut shot count): what a replay shows
  // in the GUI's Plan panel instead of the plan that was not used.
  std::optional<acq::MeasurementPlan> capture_plan;
  int shots = 0;
  int shots_averaged = 0;         // transient dut shots averaged before the Prony fit
  std::string awg_idn, daq_idn;  // *IDN? of the instruments used (empty for a replay)
  // The fixture measured from the capture's calibration shots (role open,
  // short, load), when it has any: its Cp and R1 error correct the measured
  // capacitance, its skew is removed before the port fit, and the diagnosis
  // takes Cp, lead R, R1 error and skew as measured effects.
  std::optional<dsp::FixtureCalibration> fixture;
  std::string fixture_model;  // which standards / fixture model
  std::vector<Curve> curves;  // measured (Prony), FFT, cross-spectra, original model, updated model
  std::vector<double> resonances_hz, antiresonances_hz;
  std::vector<double> singular_values;  // normalised, for the order plot
  // Per-mode figures (fs, fp, k_eff, Qm, BVD branch; C^T and tan δ at 1 kHz):
  // the output-error fit's updated model's modes when it converged (issue
  // 34), else those of the Prony-SS estimate above (capture_mode_figures.hpp).
  std::optional<CaptureModeFigures> mode_figures;
  int order = 0;
  std::vector<ParamRow> params;
  std::string update_method;  // "output-error" | "cmcm" | "lm": whose constants `updated` holds
  std::string verdict;
  std::optional<update::GapDiagnosis> diagnosis;
  std::optional<CorrectedConstants> corrected;  // the params' `updated` are these (see ParamRow)
  std::optional<update::OeResult> output_error;  // the output-error fit (issue 17), when it ran
  std::string output_error_excitation;          // the drive of the shots it fitted
  std::string heldout_path;  // the held-out capture, when there is one
  std::vector<StageReport> stages;
  // The work each phase of the run did (FE modal solves, Prony decompositions,
  // FFTs; jobs/pipeline/work.hpp): deterministic, asserted by the tests.
  std::vector<WorkPhase> work;
  std::vector<std::string> warnings;
  // The damping of the seed chain's model curves read from the first two
  // resonances (when the seed chain's constants are used): the model and
  // value with its sigma and the measured per-mode Qm (issue 19).
  std::string damping_from_resonances;
};

struct PipelineProgress {
  double fraction = 0;  // 0..1 over all stages
  std::string stage;
};

// Throws on failure with a message that says what to do; checks `cancel`
// between and inside stages (a cancelled run returns what it has).
PipelineResult run_pipeline(const PipelineRequest& req,
                            const std::function<void(const PipelineProgress&)>& progress,
                            const std::atomic<bool>& cancel);

}  // namespace piezo::jobs
