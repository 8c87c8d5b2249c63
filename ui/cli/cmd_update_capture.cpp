// `piezobench update CAP.h5 [--method oe|cmcm|lm|all]`: the tube's constants
// straight from a capture. oe (default): the output-error fit of the FE port
// model to the recorded samples (update/output_error.hpp), with a sigma and a
// status per constant. cmcm / lm: the seed's chain — Prony-SS impedance,
// features, extended CMCM or least squares on them. all: every method side by
// side (the top-level answer is oe's), so the seed's method is always compared
// with ours.
#include "ui/cli/cmd_update_capture.hpp"

#include <cmath>
#include <cstdio>

#include "acquisition/contained_read.hpp"
#include "acquisition/impedance_assessment.hpp"
#include "model/material_presets.hpp"
#include "model/material_spec.hpp"
#include "model/tube_model.hpp"
#include "ui/capture_fit.hpp"
#include "ui/nominal_material.hpp"
#include "ui/output_error_json.hpp"
#include "update/least_squares.hpp"
#include "update/updater.hpp"

namespace piezo::cli {

namespace {
namespace pm = piezo::model;
namespace pu = piezo::update;

nlohmann::json params_of(const pu::TubeParams& p) { return ui::tube_params_json(p); }

nlohmann::json oe_json(const ui::CaptureFit& f) { return ui::output_error_json(f.result, f.excitation); }

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
  const ui::CaptureModel m = ui::capture_model(cap, material, isotropic);
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

void run_update_capture(Context& ctx, const std::string& file, const std::string& method,
                        const std::string& material_option, bool isotropic, const update::OeOptions& oe) {
  if (method != "oe" && method != "cmcm" && method != "lm" && method != "all")
    throw InputError("--method for a capture must be oe, cmcm, lm or all");
  const auto cap = acq::read_capture_contained(file);  // a crash of libhdf5 costs the file only
  // --material, else the capture's own (a description naming a preset, or none: a warning).
  const auto nm = ui::nominal_material(material_option, cap.setup.material);
  const std::string& material = nm.name;
  if (nm.warning) std::fprintf(stderr, "piezobench: update: %s: %s\n", file.c_str(), nm.warning->c_str());
  ui::CaptureFitRequest req;
  req.material = material;
  req.isotropic = isotropic;
  req.options = oe;
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
    ui::CaptureFit f;
    try {
      f = ui::fit_capture(cap, req);
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

  if (ctx.json) {
    print_json(out);
  } else {
    std::printf("model updating of %s (%s, %s class, material %s): %s\n", file.c_str(), method.c_str(),
                out["model_class"].get<std::string>().c_str(), material.c_str(),
                converged ? "converged" : "NOT converged");
    if (!out.value("message", std::string()).empty())
      std::printf("  %s\n", out["message"].get<std::string>().c_str());
    for (const auto& [name, m] : methods.items()) {
      if (!m.contains("updated")) {
        std::printf("  %-5s %s\n", name.c_str(), m.value("message", std::string()).c_str());
        continue;
      }
      const auto& u = m["updated"];
      std::printf("  %-5s YE11 %.5g  nu12 %.4f  d31 %.5g  epsT33_rel %.5g  (%s)\n", name.c_str(),
                  u["YE11"].get<double>(), u["nu12"].get<double>(), u["d31"].get<double>(),
                  u["epsT33_rel"].get<double>(), m["status"].get<std::string>().c_str());
    }
    if (methods.contains("oe") && methods["oe"].contains("parameters")) {
      std::printf("  output-error fit: %-10s %14s %12s  %s\n", "", "value", "sigma", "status");
      for (const auto& p : methods["oe"]["parameters"])
        std::printf("    %-10s %14.6g %12.3g  %s%s%s\n", p["name"].get<std::string>().c_str(),
                    p["value"].get<double>(), p["sigma"].get<double>(),
                    p["status"].get<std::string>().c_str(),
                    p["note"].get<std::string>().empty() ? "" : ": ",
                    p["note"].get<std::string>().c_str());
      const auto& fit = methods["oe"]["fit"];
      std::printf("    corr(nu12, d31) %.3f; chi2/dof %.3g (noise from %s); %d shot(s), band %.0f Hz\n",
                  methods["oe"]["corr_nu12_d31"].get<double>(), fit["chi2_per_dof"].get<double>(),
                  fit["noise_source"].get<std::string>().c_str(), fit["shots"].get<int>(),
                  fit["band_hz"].get<double>());
    }
  }
  if (!converged) ctx.exit_code = kInternal;
}

}  // namespace piezo::cli
