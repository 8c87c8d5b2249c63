// `piezobench diagnose FIT.h5 [--holdout OTHER.h5] --material NAME [--isotropic|--transverse]
//      [--json] [--plot OUT.png] [--plot-size WxH] [--candidates a,b,...]`
// Issue 7: the sim-to-real gap of a recorded capture. Replays FIT.h5 through
// the pipeline (estimate Z, update the model with CMCM) and diagnoses what the
// updated model still misses — where in frequency, of what kind, which effect
// of the catalogue explains it — judged on OTHER.h5 (another capture of the
// same transducer, e.g. a chirp) or, without it, on other shots of FIT.h5.
// Exit codes: 0 diagnosed (whatever the verdict); 2 bad input: a missing or
// invalid file, too few dut shots, a diagnosis that could not run (each named
// with its file); 1 internal failure.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>

#include "acquisition/capture_file.hpp"
#include "acquisition/contained_read.hpp"
#include "model/material_presets.hpp"
#include "ui/nominal_material.hpp"
#include "ui/cli/cli_common.hpp"
#include "ui/cli/diagnosis_text.hpp"
#include "ui/pipeline.hpp"
#include "ui/report/diagnosis_plot.hpp"
#include "ui/report_export.hpp"
#include "update/gap_diagnosis.hpp"

namespace piezo::cli {

namespace {

namespace fs = std::filesystem;

struct DiagnoseArgs {
  std::string fit, holdout, material, plot, plot_size = "1200x800";
  std::vector<std::string> candidates;
  bool isotropic = false, transverse = false;
  update::OeOptions oe;
};

void require_file(const std::string& path, const char* what) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(path + ": no such file (" + what + ")");
  if (!fs::is_regular_file(path, ec)) throw InputError(path + ": not a file (" + what + ")");
}

std::pair<int, int> parse_size(const std::string& s) {
  int w = 0, h = 0;
  char x = 0, rest = 0;
  if (std::sscanf(s.c_str(), "%d%c%d%c", &w, &x, &h, &rest) != 3 || (x != 'x' && x != 'X'))
    throw InputError("--plot-size: expected WIDTHxHEIGHT, e.g. 1200x800, got '" + s + "'");
  if (w < 800 || h < 560 || w > 8000 || h > 8000)  // below 800x560 the labels crowd the panels
    throw InputError("--plot-size: " + s + " is outside 800x560 .. 8000x8000");
  return {w, h};
}

acq::Capture capture_attributes(const std::string& path) {
  acq::ContainedReadOptions ro;
  ro.read.load_samples = false;  // attributes only: quick, and the file is validated
  return acq::read_capture_contained(path, ro);  // a crash of libhdf5 costs the file only
}

// The diagnosis needs a transient dut shot in each capture (checked here
// first, so that a capture without one is refused before the update). With 3
// or more of one drive it works on Z(f) and measures the noise from the
// repeats; with one or two, in the output-error model (the pipeline decides).
void require_transient_shot(const acq::Capture& cap, const std::string& path) {
  for (const auto& s : cap.shots)
    if (s.role == acq::Role::Dut && s.excitation != acq::Excitation::Sine) return;
  throw InputError(path + ": no transient dut shot (exp_decay, chirp, noise, step): nothing to diagnose; "
                   "record one with `piezobench measure`");
}

// The nominal material: --material, else the one the capture names (a
// description naming a preset, or none, is a warning: ui/nominal_material.hpp).
std::string nominal_material(const DiagnoseArgs& a, const acq::Capture& fit, std::vector<std::string>& warnings) {
  const auto nm = ui::nominal_material(a.material, fit.setup.material);
  if (nm.warning) {
    std::fprintf(stderr, "piezobench: diagnose: %s: %s\n", a.fit.c_str(), nm.warning->c_str());
    warnings.push_back(*nm.warning);
  }
  return nm.name;
}

void check_candidates(const std::vector<std::string>& c) {
  const auto ok = update::supported_gap_effects();
  for (const auto& n : c)
    if (std::find(ok.begin(), ok.end(), n) == ok.end()) {
      std::string list;
      for (const auto& o : ok) list += (list.empty() ? "" : ", ") + o;
      throw InputError("--candidates: '" + n + "' is not an effect the diagnosis can fit (" + list +
                       ")");
    }
}

// The stages' notes that explain a diagnosis that did not run.
std::string why_not_diagnosed(const ui::PipelineResult& r) {
  std::string why = "the gap diagnosis did not run";
  for (const auto& s : r.stages)
    if (s.name == "diagnose" && !s.ran) why += ": " + s.note;
  for (const auto& s : r.stages)
    if (s.name == "update" && !s.ran) why += " (" + s.note + ")";
  return why;
}

nlohmann::json context_json(const DiagnoseArgs& a, const std::string& material,
                            const ui::PipelineResult& r, const std::string& plot) {
  nlohmann::json j;
  j["capture"] = a.fit;
  j["holdout_capture"] = a.holdout.empty() ? nlohmann::json(nullptr) : nlohmann::json(a.holdout);
  j["material"] = material;
  j["material_class"] = a.transverse ? "transversely isotropic" : "isotropic";
  j["shots"] = r.shots;
  j["parameters"] = nlohmann::json::array();
  for (const auto& p : r.params)
    j["parameters"].push_back(
        {{"name", p.name}, {"unit", p.unit}, {"original", p.original}, {"updated", p.updated}});
  j["stages"] = nlohmann::json::array();
  for (const auto& s : r.stages)
    j["stages"].push_back({{"name", s.name}, {"ran", s.ran}, {"note", s.note}});
  j["plot"] = plot.empty() ? nlohmann::json(nullptr) : nlohmann::json(plot);
  j["warnings"] = r.warnings;
  return j;
}

// Which data the plot shows and which it was judged on (the held-out data as
// the diagnosis found them when no --holdout was given).
std::string plot_subtitle(const DiagnoseArgs& a, const std::string& material,
                          const update::GapDiagnosis& d) {
  std::string t = "fit: " + fs::path(a.fit).filename().string() + "; ";
  if (!a.holdout.empty())
    t += "held out: " + fs::path(a.holdout).filename().string() +
         (d.method == "output-error" ? " (predicted from its v1)" : "");
  else
    t += d.heldout_description.empty() ? std::string("no held-out data") : d.heldout_description;
  return t + "; nominal " + material + (a.transverse ? ", transversely isotropic" : ", isotropic") +
         " class";
}

void run_diagnose(Context& ctx, const DiagnoseArgs& a) {
  require_file(a.fit, "the fit capture");
  if (!a.holdout.empty()) require_file(a.holdout, "--holdout");
  check_candidates(a.candidates);
  std::pair<int, int> size{0, 0};
  if (!a.plot.empty()) {
    size = parse_size(a.plot_size);
    const fs::path dir = fs::absolute(a.plot).parent_path();
    std::error_code ec;
    if (!fs::is_directory(dir, ec))
      throw InputError("--plot " + a.plot + ": no folder " + dir.string());
  }
  const acq::Capture fit_attrs = capture_attributes(a.fit);
  std::vector<std::string> material_warnings;
  const std::string material = nominal_material(a, fit_attrs, material_warnings);
  require_transient_shot(fit_attrs, a.fit);
  if (!a.holdout.empty()) require_transient_shot(capture_attributes(a.holdout), a.holdout);

  ui::PipelineRequest req;
  req.replay_capture = a.fit;
  req.heldout_capture = a.holdout;
  req.material = material;
  req.isotropic = !a.transverse;
  req.gap_candidates = a.candidates;
  req.oe_options = a.oe;
  std::atomic<bool> cancel{false};
  ui::PipelineResult res;
  {
    ProgressBar bar("diagnose");
    try {
      res = ui::run_pipeline(
          req, [&](const ui::PipelineProgress& p) { bar.update(p.fraction, p.stage); }, cancel);
    } catch (const std::invalid_argument& e) {  // e.g. no transient dut shot to estimate Z from
      throw InputError(a.fit + ": " + e.what());
    }
  }
  res.warnings.insert(res.warnings.begin(), material_warnings.begin(), material_warnings.end());
  if (!res.diagnosis) throw InputError(a.fit + ": " + why_not_diagnosed(res));
  const auto& d = *res.diagnosis;
  if (!a.holdout.empty() && d.n_heldout == 0)
    throw InputError(a.holdout +
                     ": fewer than 3 transient dut shots; the held-out data could not be used");

  std::string plot;
  if (!a.plot.empty()) {
    report::DiagnosisPlotOptions po;
    po.width = size.first;
    po.height = size.second;
    po.subtitle = plot_subtitle(a, material, d);
    report::write_diagnosis_png(d, po, a.plot);
    plot = a.plot;
  }

  if (ctx.json) {
    nlohmann::json j = ui::diagnosis_json(d);
    j.update(context_json(a, material, res, plot));  // context fields; none of the names
    print_json(j);
    return;
  }
  std::cout << "piezobench diagnose " << a.fit
            << (a.holdout.empty() ? "" : " --holdout " + a.holdout) << " (" << material << ", "
            << (a.transverse ? "transversely isotropic" : "isotropic") << " class)\n";
  for (const auto& s : res.stages)
    std::cout << "  " << (s.ran ? "[ran]     " : "[skipped] ") << s.name << ": " << s.note << "\n";
  if (!res.params.empty()) {
    std::printf("\n  %-12s %14s %14s\n", "parameter", "original", "updated");
    for (const auto& p : res.params)
      std::printf("  %-12s %14.6g %14.6g\n", p.name.c_str(), p.original, p.updated);
  }
  print_diagnosis(std::cout, d);
  for (const auto& w : res.warnings) std::cout << "  warning: " << w << "\n";
  if (!plot.empty()) std::cout << "\n  plot: " << plot << "\n";
}

}  // namespace

void register_diagnose_command(CLI::App& app, Context& ctx) {
  auto* c = app.add_subcommand(
      "diagnose",
      "Diagnose the sim-to-real gap of a capture: where, what kind, which unmodelled effect");
  auto a = std::make_shared<DiagnoseArgs>();
  c->add_option("FIT", a->fit, "Capture to update the model with and diagnose (.h5)")->required();
  c->add_option(
      "--holdout", a->holdout,
      "Held-out capture of the same transducer (e.g. a chirp); default: other shots of FIT");
  c->add_option("--material", a->material,
                "Nominal material preset (default: the capture's /setup/material)");
  auto* iso = c->add_flag("--isotropic", a->isotropic, "The seed's isotropic class (the default)");
  auto* tr = c->add_flag("--transverse", a->transverse, "Transversely isotropic class instead");
  iso->excludes(tr);
  c->add_option("--plot", a->plot,
                "Write a PNG: |Z| measured vs model before/after, residual, regions");
  c->add_option("--plot-size", a->plot_size, "PNG size WIDTHxHEIGHT")->capture_default_str();
  c->add_option("--candidates", a->candidates,
                "Effects to try, comma-separated (default: all supported)")
      ->delimiter(',');
  add_chain_tolerance_options(c, a->oe);
  add_json_flag(c, ctx);
  c->callback([&ctx, a] { ctx.exit_code = run_command(ctx, [&] { run_diagnose(ctx, *a); }); });
}

}  // namespace piezo::cli
