// The jobs' room (jobs/): a capture's constants (see update_capture_job.hpp).
#include "jobs/update_capture_job.hpp"

#include <algorithm>
#include <cmath>

#include "acquisition/contained_read.hpp"
#include "acquisition/impedance_assessment.hpp"
#include "jobs/job_error.hpp"
#include "jobs/json/output_error_json.hpp"
#include "jobs/nominal_material.hpp"
#include "jobs/pipeline/capture_fit.hpp"
#include "model/material_presets.hpp"
#include "model/material_spec.hpp"
#include "model/tube_model.hpp"
#include "update/least_squares.hpp"
#include "update/updater.hpp"

namespace piezo::jobs {

namespace {
namespace pm = piezo::model;
namespace pu = piezo::update;

nlohmann::json params_of(const pu::TubeParams& p) { return jobs::tube_params_json(p); }

nlohmann::json oe_json(const jobs::CaptureFit& f) { return jobs::output_error_json(f.result, f.excitation); }

// The seed's chain on a capture: Prony-SS features, then CMCM or LM.
nlohmann::json feature_methods(const acq::Capture& cap, const std::string& material, bool isotropic,
                               bool cmcm, bool lm) {
  nlohmann::json out;
  acq::AssessmentOptions ao;
  ao.kk = false;
  ao.validity = false;
  ao.stabilization = false;
  ao.uncertainty = acq::UncertaintySource::None;
  ao.prony.bootstrap = 0;
  pu::MeasuredFeatures mf;
  try {
    const auto z = acq::assess_impedance(cap, ao).result;
    for (std::size_t k = 0; k < std::min<std::size_t>(3, z.features.resonances.size()); ++k)
      mf.resonances_hz.push_back(z.features.resonances[k].f_hz);
    for (std::size_t k = 0; k < std::min<std::size_t>(3, z.features.antiresonances.size()); ++k)
      mf.antiresonances_hz.push_back(z.features.antiresonances[k].f_hz);
    mf.low_z_hz = 400.0;
    mf.low_z_ohm = 1.0 / (2 * M_PI * mf.low_z_hz * z.features.capacitance_f);
    mf.validate();
  } catch (const std::exception& e) {
    const nlohmann::json fail = {{"converged", false}, {"status", "bad_input"},
                                 {"message", std::string("no features from the Prony-SS estimate: ") + e.what()}};
    if (cmcm) out["cmcm"] = fail;
    if (lm) out["lm"] = fail;
    return out;
  }
  const nlohmann::json feats = {{"resonances_hz", mf.resonances_hz},
                                {"antiresonances_hz", mf.antiresonances_hz},
                                {"low_z_ohm", mf.low_z_ohm},
                                {"low_z_hz", mf.low_z_hz}};
  const jobs::CaptureModel m = jobs::capture_model(cap, material, isotropic);
  const pm::TubeModel& tube = *m.tube;
  pm::ModalSolver& solver = *m.solver;
  const auto& cls = m.cls;
  const auto& p0 = m.p0;
  if (cmcm) {
    pu::UpdateOptions uo;
    uo.max_sweeps = 40;
    uo.sweep_tolerance = 1e-6;
    const auto r = pu::update_cmcm(tube, solver, cls, p0, mf, uo);
    out["cmcm"] = {{"method", "cmcm"},          {"converged", r.ok()},
                   {"status", pu::to_string(r.status)}, {"message", r.message},
                   {"updated", params_of(r.updated)}, {"features", feats},
                   {"seconds", r.seconds}};
  }
  if (lm) {
    const auto r = pu::update_lm(tube, solver, cls, p0, mf);
    out["lm"] = {{"method", "lm"},          {"converged", r.ok()},
                 {"status", pu::to_string(r.status)}, {"message", r.message},
                 {"updated", params_of(r.updated)}, {"features", feats},
                 {"seconds", r.seconds}};
  }
  return out;
}

}  // namespace

UpdateCaptureResult run_update_capture(const UpdateCaptureRequest& r) {
  const std::string& file = r.file;
  const std::string& method = r.method;
  const bool isotropic = r.isotropic;
  if (method != "oe" && method != "cmcm" && method != "lm" && method != "all")
    throw InputError("--method for a capture must be oe, cmcm, lm or all");
  const auto cap = acq::read_capture_contained(file);  // a crash of libhdf5 costs the file only
  // --material, else the capture's own (a description naming a preset, or none: a warning).
  const auto nm = jobs::nominal_material(r.material, cap.setup.material);
  const std::string& material = nm.name;
  if (nm.warning && r.warn) r.warn(*nm.warning);
  jobs::CaptureFitRequest req;
  req.material = material;
  req.isotropic = isotropic;
  req.options = r.oe;
  nlohmann::json out;
  out["capture"] = file;
  out["method"] = method;
  out["model_class"] = isotropic ? "isotropic" : "transversely_isotropic";
  out["material"] = material;
  if (nm.warning) out["warnings"].push_back(*nm.warning);
  // (an unknown material throws here: exit 2)
  out["original"] = params_of(pm::isotropic_params(pm::resolve_material({material, isotropic, ""}).d));
  nlohmann::json methods;
  if (method == "oe" || method == "all") {
    jobs::CaptureFit f;
    try {
      f = jobs::fit_capture(cap, req);
    } catch (const std::invalid_argument& e) {
      throw InputError(e.what());
    }
    methods["oe"] = oe_json(f);
  }
  if (method != "oe") {
    auto fm = feature_methods(cap, material, isotropic, method == "cmcm" || method == "all",
                              method == "lm" || method == "all");
    for (auto& [k, v] : fm.items()) methods[k] = v;
  }
  const std::string lead = method == "all" ? "oe" : method;
  const auto& top = methods[lead];
  for (const char* k : {"converged", "status", "message", "updated", "parameters", "correlation",
                        "corr_nu12_d31", "damping", "fit", "features", "seconds"})
    if (top.contains(k)) out[k] = top[k];
  if (method == "all") out["methods"] = methods;
  const bool converged = top.value("converged", false);
  return {std::move(out), std::move(methods), material, converged};
}

}  // namespace piezo::jobs
