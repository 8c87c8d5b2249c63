#pragma once
// The pipeline's room (jobs/pipeline): the stages run_pipeline (pipeline.cpp)
// calls, one file each — acquire_stage, calibrate_stage, estimate_stage,
// update_stage, diagnose_stage. Internal to the pipeline: callers use
// pipeline.hpp. Each stage records what it did in PipelineResult::stages.
#include <atomic>
#include <complex>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "acquisition/capture.hpp"
#include "acquisition/sim_setup.hpp"
#include "dsp/impedance_types.hpp"
#include "jobs/pipeline/capture_fit.hpp"
#include "jobs/pipeline/pipeline.hpp"
#include "jobs/pipeline/work.hpp"
#include "model/modal.hpp"
#include "update/feature_update.hpp"

namespace piezo::jobs::detail {

struct Stages {
  const std::function<void(const PipelineProgress&)>& cb;
  WorkLog* work = nullptr;  // each label opens a phase of the work log (work.hpp)
  void operator()(double f, const std::string& s) const {
    if (work) work->open(s);
    if (cb) cb(PipelineProgress{f, s});
  }
};

// acquire_stage.cpp
acq::Capture acquire(const PipelineRequest& req, PipelineResult& out, const Stages& progress,
                     const std::atomic<bool>& cancel, std::shared_ptr<drivers::sim::SimBench>& sim);
acq::Capture acquire_heldout(const PipelineRequest& req, const acq::MeasurementPlan& plan,
                             std::shared_ptr<drivers::sim::SimBench>& sim, PipelineResult& out,
                             const std::atomic<bool>& cancel);

// calibrate_stage.cpp
void calibrate_stage(const acq::Capture& cap, PipelineResult& out);

// estimate_stage.cpp
dsp::ImpedanceResult estimate(const acq::Capture& cap, bool refine_features, PipelineResult& out);

// update_stage.cpp
struct UpdateOutcome {
  bool ok = false;
  std::string method;  // "output-error" | "cmcm" | "lm"
  update::TubeParams updated;
  model::RayleighDamping damping;
  double first_resonance_hz = 50e3;
};

// The seed's chain (chapter 6-7): extended CMCM on the estimate's features,
// least squares (LM) on the same features where CMCM does not converge (or
// beside it, `req.compare_lm`). Never throws: its failure is a stage note.
struct SeedUpdate {
  UpdateOutcome chosen;                     // CMCM's, else LM's: only where its status is converged (issue 40)
  std::optional<update::TubeParams> cmcm, lm;
  std::optional<update::FeatureUpdate> cmcm_run, lm_run;  // each method's answer, honest status and sigmas
  std::string refused;                      // why neither holds ("" when one does, or the chain did not run)
};

model::RayleighDamping damping_from_features(const dsp::ImpedanceResult& z, PipelineResult& out,
                                             const model::ModalPortModel* port);
std::vector<std::complex<double>> model_z(model::ModalSolver& solver, const model::PiezoMaterialE& m,
                                          const std::vector<double>& f, const model::RayleighDamping& d);
SeedUpdate seed_update_stage(const PipelineRequest& req, const acq::Capture& cap, const CaptureModel& cm,
                             const dsp::ImpedanceResult& z, PipelineResult& out);
std::vector<std::string> scanned_effects(const PipelineRequest& req);
std::optional<update::OeResult> output_error_stage(const PipelineRequest& req, const acq::Capture& cap,
                                                   const CaptureModel& cm, PipelineResult& out);
double first_active_mode_hz(model::ModalSolver& solver, const model::PiezoMaterialE& m);
void parameter_rows(const update::TubeParams& p0, const UpdateOutcome& u, const SeedUpdate& seed,
                    const std::optional<update::OeResult>& oe, const drivers::sim::SimBench* sim,
                    PipelineResult& out);

// diagnose_stage.cpp
// The result corrected for the effect the diagnosis named (corrected_constants.cpp):
// from the output-error fit's refit with it (`r`: the fit the diagnosis used),
// or from the impedance-domain diagnosis' own refit. No effect named: nothing.
void correct_constants(const PipelineRequest& req, const acq::Capture& cap, const CaptureModel& cm,
                       const update::OeResult* r, PipelineResult& out);

void diagnose_stage(const PipelineRequest& req, const acq::Capture& cap, const CaptureModel& cm,
                    const acq::Capture* heldout_cap, const UpdateOutcome& u, PipelineResult& out,
                    const Stages& progress, const std::atomic<bool>& cancel);

}  // namespace piezo::jobs::detail
