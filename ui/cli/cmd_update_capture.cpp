// `piezobench update CAP.h5 [--method oe|cmcm|lm|all]`: the tube's constants
// straight from a capture. oe (default): the output-error fit of the FE port
// model to the recorded samples (jobs/pipeline/capture_fit.hpp), with a sigma and a
// status per constant. cmcm / lm: the seed's chain — Prony-SS impedance,
// features, extended CMCM or least squares on them. all: every method side by
// side (the top-level answer is oe's), so the seed's method is always compared
// with ours.
#include "ui/cli/cmd_update_capture.hpp"

#include <cmath>
#include <cstdio>

#include "jobs/text/user_message.hpp"
#include "jobs/text/uncertain_text.hpp"
#include "jobs/update_capture_job.hpp"

namespace piezo::cli {

void run_update_capture(Context& ctx, const std::string& file, const std::string& method,
                        const std::string& material_option, bool isotropic, const update::OeOptions& oe) {
  jobs::UpdateCaptureRequest req;
  req.file = file;
  req.method = method;
  req.material = material_option;
  req.isotropic = isotropic;
  req.oe = oe;
  req.warn = [&](const std::string& w) {
    std::fprintf(stderr, "piezobench: update: %s: %s\n", file.c_str(), jobs::user_message(w).c_str());
  };
  auto r = jobs::run_update_capture(req);
  nlohmann::json& out = r.json;
  nlohmann::json& methods = r.methods;
  const std::string& material = r.material;
  const bool converged = r.converged;

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
    // The seed's chain (issue 40): each constant with its sigma and status, the reason of a refusal.
    for (const char* name : {"cmcm", "lm"}) {
      if (!methods.contains(name) || !methods[name].contains("parameters")) continue;
      const auto& m = methods[name];
      std::printf("  %s: %s%s%s\n", name, m.value("status", std::string()).c_str(),
                  m.value("message", std::string()).empty() ? "" : ": ", m.value("message", std::string()).c_str());
      for (const auto& p : m["parameters"])
        std::printf("    %-10s %14.6g %12.3g  %s%s%s\n", p["name"].get<std::string>().c_str(), p["value"].get<double>(),
                    p["sigma"].is_number() ? p["sigma"].get<double>() : NAN, p["status"].get<std::string>().c_str(),
                    p["note"].get<std::string>().empty() ? "" : ": ", p["note"].get<std::string>().c_str());
    }
    if (methods.contains("oe") && methods["oe"].contains("parameters")) {
      std::printf("  output-error fit: %-10s %-28s  %s\n", "", "value ± sigma", "status");
      for (const auto& p : methods["oe"]["parameters"])
        std::printf("    %-10s %-28s  %s%s%s\n", p["name"].get<std::string>().c_str(),
                    jobs::format_uncertain(json_number(p["value"]), json_number(p["sigma"]),
                                           p.value("unit", std::string()), {true})
                        .c_str(),
                    p["status"].get<std::string>().c_str(),
                    p["note"].get<std::string>().empty() ? "" : ": ",
                    p["note"].get<std::string>().c_str());
      const auto& fit = methods["oe"]["fit"];
      std::printf("    corr(nu12, d31) %s; chi2/dof %s (noise from %s); %d shot(s), band %.0f Hz\n",
                  jobs::format_value(json_number(methods["oe"]["corr_nu12_d31"]), {}, 3).c_str(),
                  jobs::format_value(json_number(fit["chi2_per_dof"]), {}, 3).c_str(),
                  fit["noise_source"].get<std::string>().c_str(), fit["shots"].get<int>(),
                  fit["band_hz"].get<double>());
      // Issue 33: the slow disturbances modelled, and the shots' agreement.
      if (fit.contains("baseline")) {
        const auto& b = fit["baseline"];
        if (b.value("modelled", false))
          std::printf("    baseline projected out (offset, slope to degree %d%s): chi2 %.0f for %d parameters\n",
                      b.value("poly_degree", 0), b.value("harmonics", 0) > 0 ? ", mains hum" : "",
                      b.value("delta_chi2", 0.0), b.value("dof", 0));
        if (b.contains("pink") && b["pink"].value("modelled", false))
          std::printf("    1/f noise weighted as noise: %.3g mV rms in the band\n",
                      1e3 * b["pink"].value("rms_v", 0.0));
      }
      if (fit.contains("shot_consistency")) {
        const auto& c = fit["shot_consistency"];
        if (c.value("aligned", false)) std::printf("    shots aligned for trigger jitter before averaging\n");
        if (c.value("tested", false) && !c.value("consistent", true))
          std::printf("    warning: %s\n", c.value("summary", std::string()).c_str());
      }
    }
  }
  if (!converged) ctx.exit_code = kInternal;
}

}  // namespace piezo::cli
