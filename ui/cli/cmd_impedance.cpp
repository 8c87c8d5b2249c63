// `piezobench impedance CAPTURE.h5 --method prony|fft|xspec|sine ...`: impedance of
// the "dut" shots of a capture by one of the dsp/ estimators, as text, JSON
// (features, Prony order and singular values), CSV (f_hz,re_ohm,im_ohm) or
// Touchstone 1-port (.s1p, Z, RI). The CLI's room (ui/cli): options and
// printing only; the work (estimators, trust, JSON) is jobs/impedance_job.hpp.
// Per-mode figures: key "modes" in --json always, the table after the
// impedance with --figures.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>

#include "jobs/impedance_job.hpp"
#include "jobs/json/json_text.hpp"
#include "jobs/json/mode_figures_json.hpp"
#include "jobs/text/uncertain_text.hpp"
#include "ui/cli/cli_common.hpp"

namespace piezo::cli {

namespace {

struct ImpedanceArgs {
  jobs::ImpedanceRequest req;  // the estimate's options
  std::string output;
  bool csv = false, s1p = false, figures = false;
};

void print_trust(const nlohmann::json& j) {
  const auto& c = j["compensation"];
  std::printf("  fixture model   %s\n", c["description"].get<std::string>().c_str());
  if (c.contains("fixture")) {
    const auto& f = c["fixture"];
    if (f.contains("fixture_capacitance_f"))
      std::printf("  fixture C       %.4g pF (measured, open)\n", f["fixture_capacitance_f"].get<double>() * 1e12);
    if (f.contains("lead_resistance_ohm"))
      std::printf("  lead R          %.4g ohm (measured, short)\n", f["lead_resistance_ohm"].get<double>());
    if (f.contains("r1_error"))
      std::printf("  R1 error        %+.3f %% (measured, load)\n", f["r1_error"].get<double>() * 100);
  }
  const auto& d = j["deskew"];
  if (d["applied"].get<bool>())
    std::printf("  channel skew    %.2f ns removed (%s)\n", d["skew_ns"].get<double>(), d["source"].get<std::string>().c_str());
  if (j.contains("kramers_kronig"))
    std::printf("  Kramers-Kronig  %s (%s)\n", j["kramers_kronig"]["pass"].get<bool>() ? "pass" : "FAIL",
                j["kramers_kronig"]["note"].get<std::string>().c_str());
  if (j.contains("uncertainty"))
    std::printf("  uncertainty     %s, k = %.2f\n", j["uncertainty"]["source"].get<std::string>().c_str(),
                j["uncertainty"]["coverage_factor"].get<double>());
  if (j.contains("validity"))
    for (const auto& s : j["validity"]["shots"])
      if (!s["flags"].empty())
        std::printf("  shot %s       %s\n", s["name"].get<std::string>().c_str(), s["flags"].dump().c_str());
  for (const auto& n : j["notes"]) std::printf("  note: %s\n", n.get<std::string>().c_str());
}

void print_text(const nlohmann::json& j) {
  std::printf("%s  method %s, %zu samples\n", j["file"].get<std::string>().c_str(),
              j["method"].get<std::string>().c_str(), j["samples_used"].get<std::size_t>());
  if (j.contains("order"))
    std::printf("  model order     %zu (%s)\n", j["order"].get<std::size_t>(),
                j["order_automatic"].get<bool>() ? "automatic" : "manual");
  const auto& f = j["features"];
  // Only the features that stand clear of their σ (features.*_significant);
  // how many candidates were left out is said.
  auto row = [&](const char* name, const char* key, const char* skey, const char* sigkey) {
    std::printf("  %-15s", name);
    std::size_t shown = 0, left = 0, outside = 0;
    const std::string inkey = std::string(key).substr(0, std::string(key).size() - 3) + "_in_drive_band";
    for (std::size_t k = 0; k < f[key].size(); ++k) {
      if (f.contains(inkey) && k < f[inkey].size() && f[inkey][k].is_boolean() && !f[inkey][k].get<bool>()) {
        ++outside;
        continue;
      }
      if (f.contains(sigkey) && k < f[sigkey].size() && f[sigkey][k].is_boolean() && !f[sigkey][k].get<bool>()) {
        ++left;
        continue;
      }
      ++shown;
      // σ to two significant digits, the value to match (jobs/text/uncertain_text.hpp).
      const double v = json_number(f[key][k]);
      if (f[skey].is_array() && k < f[skey].size() && f[skey][k].is_number())
        std::printf(" %s;", jobs::format_uncertain(v, f[skey][k].get<double>(), "Hz").c_str());
      else
        std::printf(" %s;", jobs::format_value(v, "Hz", 7).c_str());
    }
    if (!shown) std::printf(" none significant");
    if (left) std::printf(" (%zu candidate(s) without significance not listed: sigma not below a third of the frequency)", left);
    if (outside) std::printf(" (%zu candidate(s) outside the drive's band not listed)", outside);
    std::printf("\n");
  };
  row("resonances", "resonances_hz", "resonances_sigma_hz", "resonances_significant");
  row("antiresonances", "antiresonances_hz", "antiresonances_sigma_hz", "antiresonances_significant");
  if (f["capacitance_f"].is_number())
    std::printf("  capacitance     %s\n", jobs::format_value(f["capacitance_f"].get<double>() * 1e12, "pF", 5).c_str());
  if (j.contains("drive_band") && j["drive_band"]["found"].get<bool>())
    std::printf("  drive band      %s to %s (channel 1 above its noise floor)\n",
                jobs::format_value(j["drive_band"]["lo_hz"].get<double>(), "Hz", 3).c_str(),
                jobs::format_value(j["drive_band"]["hi_hz"].get<double>(), "Hz", 3).c_str());
}

void run(const ImpedanceArgs& a, Context& ctx) {
  if (int(a.csv) + int(a.s1p) + int(ctx.json) > 1) throw InputError("choose one of --json, --csv, --s1p");
  const jobs::ImpedanceJobResult r = jobs::run_impedance(a.req);
  std::ofstream file;
  std::ostream* os = &std::cout;
  if (!a.output.empty()) {
    file.open(a.output);
    if (!file) throw InputError("cannot write " + a.output);
    os = &file;
  }
  if (a.csv) {
    jobs::write_impedance_csv(*os, r);
  } else if (a.s1p) {
    jobs::write_impedance_s1p(*os, r);
  } else {
    auto j = jobs::impedance_json(a.req, r);
    if (ctx.json || a.figures) jobs::add_impedance_mode_figures(j, r);
    if (ctx.json) {
      jobs::write_json(*os, j);  // streamed, no serialised copy
      *os << std::endl;
    } else {
      print_text(j);
      print_trust(j);
      if (a.figures) jobs::print_mode_figures(stdout, j["modes"], j["mode_summary"]);
    }
  }
}

// The estimators' labels, and --method's help: their keys, then one line each
// (acq::builtin_estimators(), acquisition/estimators/estimator.hpp).
std::string estimator_labels() {
  std::string out;
  for (const auto& e : acq::builtin_estimators().entries()) out += (out.empty() ? "" : ", ") + e.label;
  return out;
}

std::string method_help() {
  std::string out = acq::join_keys(acq::builtin_estimators().keys(), " | ", " | ");
  for (const auto& e : acq::builtin_estimators().entries()) out += "\n  " + e.key + ": " + e.description;
  return out;
}

}  // namespace

void register_impedance_command(CLI::App& app, Context& ctx) {
  auto a = std::make_shared<ImpedanceArgs>();
  auto* cmd = app.add_subcommand("impedance", "Impedance of a capture's dut shots (" + estimator_labels() + ")");
  cmd->add_option("CAPTURE", a->req.file, "Capture file (.h5)")->required();
  cmd->add_option("--method", a->req.method, method_help())->check(CLI::IsMember(acq::builtin_estimators().keys()));
  cmd->add_option("--shot", a->req.shot, "One shot by index (prony, fft); default: every dut shot of the drive, averaged");
  cmd->add_option("--samples", a->req.samples, "Samples after t = 0 (prony: default 6000, as the pipeline; fft/xspec: all)");
  cmd->add_option("--order", a->req.order, "Prony model order (default: automatic)")->check(CLI::PositiveNumber);
  cmd->add_option("--fmin", a->req.fmin, "Lowest frequency [Hz] (default: one step)");
  cmd->add_option("--fmax", a->req.fmax, "Highest frequency [Hz] (default: the pipeline's, 120 kHz or fs/4 when lower)");
  cmd->add_option("--step", a->req.step, "Grid step [Hz] (default: 100 Hz, or fmax/2000 when that is wider)");
  cmd->add_option("--window", a->req.window, "fft/xspec window: rect, hann, hamming, blackman-harris, flattop, tukey");
  cmd->add_option("--segment", a->req.segment, "xspec segment length (default: the shortest shot)");
  cmd->add_option("--overlap", a->req.overlap, "xspec segment overlap fraction")->check(CLI::Range(0.0, 0.95));
  cmd->add_option("--bootstrap", a->req.bootstrap, "Prony: bootstrap refits for the feature uncertainties");
  cmd->add_flag("--csv", a->csv, "CSV output: f_hz,re_ohm,im_ohm, then the uncertainty band columns");
  cmd->add_option("--compensation", a->req.compensation,
                  "Fixture compensation from the capture's open/short/load shots: auto | none | open | short | "
                  "open-short | open-short-load")
      ->capture_default_str();
  cmd->add_flag("--no-deskew", a->req.no_deskew, "Do not estimate/remove the channel-2 skew");
  cmd->add_flag("--no-baseline", a->req.no_baseline,
                "Do not test the shots for a slow baseline (wander, mains hum) of channel 1 - channel 2");
  cmd->add_flag("--remove-baseline", a->req.remove_baseline,
                "Remove a significant slow baseline of channel 1 - channel 2 from channel 1 before the estimate");
  cmd->add_option("--skew-ns", a->req.skew_ns, "A stored channel-2 skew (ns, > 0: v2 late) for a capture without calibration shots");
  cmd->add_flag("--average", a->req.average,
                "prony/fft: average every dut shot of the drive (the default, as the pipeline's estimate)");
  cmd->add_flag("--one-shot", a->req.one_shot, "prony/fft: estimate from one shot (the first exp-decay dut shot, or --shot)");
  cmd->add_option("--uncertainty", a->req.uncertainty, "Uncertainty band: auto | shots | noise | none")->capture_default_str();
  cmd->add_option("--bootstrap-shots", a->req.bootstrap_shots, "Replicates of the bootstrap over shots")->capture_default_str();
  cmd->add_flag("--no-kk", a->req.no_kk, "Skip the Kramers-Kronig / passivity check");
  cmd->add_flag("--no-validity", a->req.no_validity, "Skip the per-shot validity flags");
  cmd->add_option("--stabilization", a->req.stabilization, "Prony stabilization chart orders MIN:MAX[:STEP]")->capture_default_str();
  cmd->add_flag("--no-stabilization", a->req.no_stabilization, "Skip the stabilization chart");
  cmd->add_flag("--figures", a->figures,
                "Per-mode figures after the impedance: fs, fp, k_eff, Qm two ways, BVD R1 L1 C1 C0 "
                "(always under \"modes\" in --json)");
  cmd->add_flag("--s1p", a->s1p, "Touchstone 1-port output (Z, RI, normalised to 50 ohm)");
  cmd->add_option("-o,--output", a->output, "Write the output to this file instead of stdout");
  add_json_flag(cmd, ctx);
  cmd->callback([&ctx, a] { ctx.exit_code = run_command(ctx, [&] { run(*a, ctx); }); });
}

}  // namespace piezo::cli
