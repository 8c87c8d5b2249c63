// The jobs' room (jobs/): a capture's constants (see update_capture_job.hpp).
#include "jobs/update_capture_job.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

#include "acquisition/contained_read.hpp"
#include "acquisition/impedance_assessment.hpp"
#include "jobs/impedance_job.hpp"
#include "jobs/job_error.hpp"
#include "jobs/json/output_error_json.hpp"
#include "jobs/nominal_material.hpp"
#include "jobs/pipeline/capture_fit.hpp"
#include "jobs/seed_features.hpp"
#include "model/material_presets.hpp"
#include "model/material_spec.hpp"
#include "model/tube_model.hpp"
#include "update/feature_update.hpp"

namespace piezo::jobs {

namespace {
namespace pm = piezo::model;
namespace pu = piezo::update;

nlohmann::json params_of(const pu::TubeParams& p) { return jobs::tube_params_json(p); }

nlohmann::json oe_json(const jobs::CaptureFit& f) { return jobs::output_error_json(f.result, f.excitation); }

// The seed's chain on a capture (issue 40): the features of the estimate
// `piezobench impedance CAP.h5 --average` gives (jobs/impedance_job: Prony-SS
// on the dut shots of the first drive averaged — one shot where there is one —,
// its band, the capture's fixture compensation; the features' σ from its
// parametric bootstrap, widened by the orders p ± 2), kept inside the drive's band and
// the model's mode range (jobs/seed_features.hpp), then extended CMCM or least
// squares with an honest status and σ (update/feature_update.hpp). The
// uncertainty band, Kramers-Kronig, validity and stabilization checks of the
// impedance command do not change its estimate or features and are skipped.
nlohmann::json feature_methods(const std::string& file, const CaptureModel& m, bool cmcm, bool lm,
                               const pu::OeOptions& chain) {
  nlohmann::json out;
  ImpedanceRequest ir;
  ir.file = file;
  ir.method = "prony";
  ir.average = true;  // repeated shots of the drive averaged (`impedance --average`): the best the capture supports
  ir.uncertainty = "none";
  ir.no_kk = ir.no_validity = ir.no_stabilization = true;
  std::optional<SeedFeatures> sf;
  try {
    auto z = run_impedance(ir);
    const auto drive = capture_drive_band(z.capture, z.shots);
    // The features' σ: Prony's bootstrap at its order, widened by the estimate at orders p ± 2.
    std::vector<dsp::ImpedanceFeatures> others;
    nlohmann::json orders = nlohmann::json::array();
    if (z.z.prony)
      for (int step : {-2, 2}) {
        const long q = static_cast<long>(z.z.prony->order) + step;
        if (q < 2) continue;
        ImpedanceRequest iq = ir;
        iq.order = static_cast<std::size_t>(q);
        iq.bootstrap = 0;
        try {
          others.push_back(run_impedance(iq).z.features);
          orders.push_back(q);
        } catch (const std::exception&) {
          // the data cannot carry that order: no spread from it
        }
      }
    widen_by_order_spread(z.z.features, others);
    // The low-frequency capacitance from the impedance command's FFT ratio
    // (`impedance CAP.h5 --method fft`): model-free, its σ from the noise. Prony's
    // depends on the order the noise sets (refsim 03: −0.43 % at order 4, its
    // bootstrap σ 0.12 %; orders 6 and 8 break down), the FFT ratio's does not
    // (03, 11, 12, 15: −0.51, −0.23, +0.12, +0.57 % of the truth, σ 0.6–1.6 %).
    ImpedanceRequest fr = ir;
    fr.method = "fft";
    std::string c_source = "the FFT ratio (impedance --method fft)";
    try {
      const auto zf = run_impedance(fr);
      z.z.features.capacitance_f = zf.z.features.capacitance_f;
      z.z.features.capacitance_sigma_f = zf.z.features.capacitance_sigma_f;
    } catch (const std::exception& e) {
      c_source = std::string("Prony-SS (the FFT ratio failed: ") + e.what() + ")";
    }
    // The measurement chain's tolerances the samples cannot tell from C (the
    // output-error fit's, OeOptions: R1 1 %, channel gain 0.5 %, 30 pF across the
    // transducer): C_m ∝ 1/R1, ∝ 1/(1 + g), C + Cp — in quadrature with the noise.
    double c_type_b = 0;
    if (z.z.features.capacitance_f > 0) {
      const double c = z.z.features.capacitance_f;
      c_type_b = c * std::sqrt(chain.r1_rel_sigma * chain.r1_rel_sigma + chain.gain_rel_sigma * chain.gain_rel_sigma +
                               (chain.cp_sigma_f / c) * (chain.cp_sigma_f / c));
      if (std::isfinite(z.z.features.capacitance_sigma_f))
        z.z.features.capacitance_sigma_f = std::hypot(z.z.features.capacitance_sigma_f, c_type_b);
    }
    sf = select_seed_features(z.z.features, z.band_hz, drive, m);
    sf->json["sigma_orders"] = orders;
    sf->json["capacitance_sigma_chain_f"] = c_type_b;
    sf->json["capacitance_source"] = c_source;
    sf->json["estimate"] = {{"method", "prony"}, {"shots", z.shots}, {"band_hz", z.band_hz},
                            {"order", z.z.prony ? nlohmann::json(z.z.prony->order) : nlohmann::json(nullptr)}};
  } catch (const std::exception& e) {
    const nlohmann::json fail = {{"converged", false}, {"status", "no_features"},
                                 {"message", std::string("no features from the Prony-SS estimate: ") + e.what()}};
    if (cmcm) out["cmcm"] = fail;
    if (lm) out["lm"] = fail;
    return out;
  }
  auto run = [&](pu::FeatureMethod fm) {
    const auto u = pu::update_from_features(*m.tube, *m.solver, m.cls, m.p0, sf->features, sf->band, fm, {},
                                            sf->no_features);
    return feature_update_json(u, *sf);
  };
  if (cmcm) out["cmcm"] = run(pu::FeatureMethod::cmcm);
  if (lm) out["lm"] = run(pu::FeatureMethod::lm);
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
    const jobs::CaptureModel cm = jobs::capture_model(cap, material, isotropic);
    auto fm = feature_methods(file, cm, method == "cmcm" || method == "all", method == "lm" || method == "all", r.oe);
    for (auto& [k, v] : fm.items()) methods[k] = v;
  }
  const std::string lead = method == "all" ? "oe" : method;
  const auto& top = methods[lead];
  for (const char* k : {"converged", "status", "message", "updated", "parameters", "correlation",
                        "corr_nu12_d31", "damping", "fit", "features", "seconds", "reason", "method_status",
                        "method_message", "residuals", "chi2", "dof", "log10_chance", "birge",
                        "eps_t33_from_capacitance"})
    if (top.contains(k)) out[k] = top[k];
  if (method == "all") out["methods"] = methods;
  const bool converged = top.value("converged", false);
  return {std::move(out), std::move(methods), material, converged};
}

}  // namespace piezo::jobs
