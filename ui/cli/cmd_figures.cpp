// `piezobench figures FILE [--json|--csv] [--plot OUT.png] [--modes N] [--band LO:HI] [--columns SPEC]`:
// per-mode figures (fs, fp, fm, fn, fr, fa, k_eff in its IEEE 176 and EN 50324-2
// forms, Qm two ways, R1 L1 C1, the misfit) with σ, from a capture or any
// impedance analyzer's file. The CLI's room (ui/cli): options and printing only;
// the work is jobs/figures_job.hpp.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>

#include "jobs/figures_job.hpp"
#include "jobs/text/uncertain_text.hpp"
#include "ui/cli/cli_common.hpp"

namespace piezo::cli {

namespace {

struct FiguresArgs {
  jobs::FiguresRequest req;
  std::string band, plot;
  bool csv = false;
};

void parse_band(const std::string& s, jobs::FiguresRequest& r) {
  const auto colon = s.find(':');
  try {
    if (colon == std::string::npos) throw std::invalid_argument("no colon");
    std::size_t used = 0;
    r.band_lo_hz = std::stod(s.substr(0, colon), &used);
    r.band_hi_hz = std::stod(s.substr(colon + 1), &used);
  } catch (const std::exception&) {
    throw InputError("--band: expected LO:HI in Hz, got '" + s + "'");
  }
}

// A figure {"value", "sigma"} with its unit: σ to two significant digits, the
// value to match, an SI prefix for F, H, Hz and ohm (jobs/text/uncertain_text.hpp).
std::string pm(const nlohmann::json& f, const char* unit = "") {
  if (!f["value"].is_number()) return "-";
  return jobs::format_si(f["value"].get<double>(), json_number(f["sigma"]), unit);
}

void print_text(const nlohmann::json& j) {
  std::printf("%s\n  source          %s: %s (%s)\n", j["file"].get<std::string>().c_str(),
              j["source"].get<std::string>().c_str(), j["format"].get<std::string>().c_str(),
              j["quantity"].get<std::string>().c_str());
  const auto& fit = j["fit"];
  std::printf("  fit             %d points, %zu modes, %d parameters, chi2/dof %s, |Z| misfit %.3g %%%s\n",
              j["points"].get<int>(), j["modes"].size(), fit["parameters"].get<int>(),
              fit["chi2_per_dof"].is_null() ? "-" : std::to_string(fit["chi2_per_dof"].get<double>()).c_str(),
              fit["misfit_abs_rel_rms"].get<double>() * 100, j["magnitude_only"].get<bool>() ? " (|Z| only)" : "");
  if (j.contains("status")) {
    std::printf("  status          %s", j["status"].get<std::string>().c_str());
    for (const auto& r : j["status_reasons"]) std::printf("; %s", r.get<std::string>().c_str());
    if (!fit["residual_to_scatter"].is_null())
      std::printf("  (residual %.3g x the data's point-to-point scatter)", fit["residual_to_scatter"].get<double>());
    std::printf("\n");
  }
  if (j.contains("output_error") && j["output_error"].contains("parameters")) {
    std::printf("  model          ");
    for (const auto& p : j["output_error"]["parameters"]) {
      const double v = json_number(p["value"]), s = json_number(p["sigma"]);
      std::printf(" %s %s%s;", p["name"].get<std::string>().c_str(),
                  jobs::format_uncertain(v, s, p.value("unit", std::string())).c_str(),
                  p["status"] == "ok" || !std::isfinite(s) ? "" : " (not identifiable)");
    }
    std::printf("\n");
  }
  const auto& c = j["circuit"];
  std::printf("  C0              %s, tan d %s, Rs %s, C^T %s\n", pm(c["c0_f"], "F").c_str(),
              pm(c["tan_delta"]).c_str(), pm(c["rs_ohm"], "ohm").c_str(), pm(c["free_capacitance_f"], "F").c_str());
  for (const auto& m : j["modes"]) {
    const double lo = std::max(m["window_hz"][0].is_null() ? 0.0 : m["window_hz"][0].get<double>(),
                               j["band_hz"][0].get<double>());
    const double hi = m["window_hz"][1].is_null() ? j["band_hz"][1].get<double>()
                                                  : std::min(m["window_hz"][1].get<double>(), j["band_hz"][1].get<double>());
    std::printf("\n  mode %d  (window %.6g-%.6g Hz, %d points, misfit %.3g %%)\n", m["mode"].get<int>(), lo, hi,
                m["points"].get<int>(), m["misfit_rel_rms"].is_null() ? 0.0 : m["misfit_rel_rms"].get<double>() * 100);
    if (m.contains("status")) {
      if (m["status"] == "ok")
        std::printf("    status ok\n");
      else
        for (const auto& r : m["reasons"]) std::printf("    UNRELIABLE: %s\n", r.get<std::string>().c_str());
      for (const auto& r : m["sigma_notes"]) std::printf("    (%s)\n", r.get<std::string>().c_str());
    }
    std::printf("    fs %s   fp %s\n", pm(m["fs_hz"], "Hz").c_str(), pm(m["fp_hz"], "Hz").c_str());
    std::printf("    fm %s   fn %s\n", pm(m["fm_hz"], "Hz").c_str(), pm(m["fn_hz"], "Hz").c_str());
    std::printf("    fr %s   fa %s\n", pm(m["fr_hz"], "Hz").c_str(), pm(m["fa_hz"], "Hz").c_str());
    std::printf("    k_eff %s (IEEE 176, fs/fp)   %s (EN 50324-2, fm/fn)\n", pm(m["k_eff_ieee176"]).c_str(),
                pm(m["k_eff_en50324"]).c_str());
    std::printf("    Qm %s (branch)   %s (bandwidth)\n", pm(m["qm_branch"]).c_str(), pm(m["qm_bandwidth"]).c_str());
    std::printf("    R1 %s   L1 %s   C1 %s\n", pm(m["r1_ohm"], "ohm").c_str(), pm(m["l1_h"], "H").c_str(),
                pm(m["c1_f"], "F").c_str());
  }
  for (const auto& n : j["notes"]) std::printf("  note: %s\n", n.get<std::string>().c_str());
  if (j.contains("warnings"))
    for (const auto& w : j["warnings"]) std::printf("  WARNING: %s\n", w.get<std::string>().c_str());
}

}  // namespace

void register_figures_command(CLI::App& app, Context& ctx) {
  auto a = std::make_shared<FiguresArgs>();
  auto* cmd = app.add_subcommand(
      "figures", "Per-mode figures with sigma from a capture (.h5) or an impedance file (Touchstone .s1p/.s2p, 4294A, E4990A, Bode 100, HIOKI, LabOne, CSV/TSV)");
  cmd->add_option("FILE", a->req.file, "Capture (.h5) or impedance file")->required();
  add_json_flag(cmd, ctx);
  cmd->add_flag("--csv", a->csv, "One CSV row per mode (value and sigma columns)");
  cmd->add_option("--plot", a->plot, "PNG of the data and the fitted network");
  cmd->add_option("--modes", a->req.max_modes, "Modes (branches) at most")->capture_default_str();
  cmd->add_option("--band", a->band, "Frequency band LO:HI in Hz (default: the data's; a capture: its estimate's)");
  // oe, then the impedance estimators that take a transient (acquisition/estimators/).
  auto methods = jobs::figures_estimators();
  cmd->add_option("--method", a->req.method,
                  "A capture's estimator: oe (default: the output-error fit's updated FE model, its modes' "
                  "figures), or " + acq::join_keys(methods) + " (the circuit fitted to that impedance estimate)")
      ->check(CLI::IsMember([&] {
        methods.insert(methods.begin(), "oe");
        return methods;
      }()));
  cmd->add_option("--material", a->req.material, "oe: the nominal material (default: the capture's own)");
  cmd->add_option("--columns", a->req.columns,
                  "A table's columns in order, as quantity[unit], e.g. f[kHz],G[uS],B[uS] or "
                  "f[Hz],|Z|[ohm],theta[deg] (- skips one); for a file without a header, or one we cannot read");
  cmd->callback([&ctx, a] {
    ctx.exit_code = run_command(ctx, [&] {
      if (!a->band.empty()) parse_band(a->band, a->req);
      const auto r = jobs::run_figures(a->req);
      if (!a->plot.empty()) jobs::write_figures_plot(r, a->plot);
      if (a->csv) {
        jobs::write_figures_csv(std::cout, r);
        return;
      }
      const auto j = jobs::figures_json(a->req, r);
      if (ctx.json)
        print_json(j);
      else
        print_text(j);
    });
  });
}

}  // namespace piezo::cli
