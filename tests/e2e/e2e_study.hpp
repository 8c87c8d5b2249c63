#pragma once
// Issue 6's end-to-end updating study (test support): one random tube on the
// simulated bench → capture (acquisition::make_sim_bench + the runner, written
// to an HDF5 capture and read back) → Z by Prony-SS on the averaged shots
// (dsp) → features → extended CMCM and Levenberg–Marquardt (update), against
// the tube's true parameters. No estimator sees the truth: it is used only to
// score the answers.
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "acquisition/plan.hpp"
#include "model/modal.hpp"
#include "update/features.hpp"
#include "update/parametrization.hpp"

namespace piezo::test {

// How the chain measures and estimates (the knobs of the study).
struct E2eChain {
  double noise_rel = 0.03;           // per channel, std(noise)/std(clean channel over the record)
  acq::MeasurementPlan plan;         // excitation, record, shots (R1 = 3140 Ω)
  std::size_t prony_samples = 6000;  // samples from t = 0 fitted (0: all)
  double band_hz = 120e3;            // estimate / feature band
  // Refine Prony's features by the output-error fit of the modal port model
  // (update/port_fit.hpp) over the same samples.
  bool port_fit = false;
  bool lm_weighted = true;  // LM residuals divided by the features' σ's (port fit only)
  model::RayleighDamping damping{0.0, 1e-7};  // the simulated tube's (seed ch. 5)
};

// The seed's lab plan (R1 = 3140 Ω, 1 V exp_decay at 3000 1/s, 20000 samples at 10 MS/s).
acq::MeasurementPlan seed_lab_plan(int shots);

// The chain of issue 6's study: 3 % noise, 16 shots of a 1 V exp_decay at
// 1e5 1/s (more drive at 50–100 kHz for the same record), Prony-SS on 6000
// samples, features refined by the output-error port fit, LM weighted by
// their σ's. And the seed's chain it replaces (exp_decay at 3000 1/s, Prony
// features only) for the record.
E2eChain issue6_chain();
E2eChain seed_chain();

struct E2eCase {
  update::TubeParams truth;
  std::uint64_t noise_seed = 1;
};

// `n` tubes with each of YE11, nu12, d31, εT33 drawn uniformly within ±`spread`
// of APC850's isotropic-class values (update/parametrization.hpp), seeded.
std::vector<E2eCase> draw_cases(int n, std::uint64_t seed, double spread = 0.15);

struct E2eMethodResult {
  bool ok = false;
  std::string message;
  update::TubeParams params;
  double err[4] = {0, 0, 0, 0};  // relative errors of YE11, nu12, d31, εT33
  double seconds = 0;            // wall time of the update call
  double max_abs_err() const;
};

struct E2eOutcome {
  E2eCase c;
  std::string failure;  // non-empty: the chain stopped before updating (why)
  update::MeasuredFeatures features;
  std::vector<double> true_resonances_hz,
      true_antiresonances_hz;  // FE model of the truth (scoring only)
  double true_capacitance_f = 0;
  int prony_order = 0;
  std::string port_fit_note;  // status of the output-error refinement (when used)
  double seconds_capture = 0, seconds_estimate = 0;
  E2eMethodResult cmcm, lm;
};

// Runs one case; `work_dir` receives the capture. Never throws for a chain
// failure (it is reported in `failure`).
E2eOutcome run_e2e_case(const E2eCase& c, const E2eChain& chain,
                        const std::filesystem::path& work_dir, model::TubeModel& tube,
                        model::ModalSolver& solver);

// Cramér–Rao bound of the four parameters from the data the chain fits:
// v2 at the first `prony_samples` samples of the averaged record (white noise
// of the chain's level, σ = noise_rel·std(clean v2)/√shots), v1 known exactly,
// the FE port model as the parametric signal model, Rayleigh α and β as
// nuisance parameters. A lower bound for any unbiased estimator of the
// parameters from this capture (optimistic: v1's noise is left out).
struct E2eCrb {
  double sigma[4] = {0, 0, 0, 0};  // relative 1-σ of YE11, nu12, d31, εT33
  double noise_v2_v = 0;           // σ of v2 after averaging (V)
};
E2eCrb e2e_crb(const update::TubeParams& truth, const E2eChain& chain, model::ModalSolver& solver);

// One table row per case, and the header.
std::string e2e_header();
std::string e2e_row(int index, const E2eOutcome& o);

}  // namespace piezo::test
