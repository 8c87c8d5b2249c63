// The jobs' room (jobs/): the gap diagnosis of a capture (see diagnose_job.hpp).
// Exit codes of the command: 0 diagnosed (whatever the verdict); 2 bad input
// (InputError here); 1 internal failure.
#include "jobs/diagnose_job.hpp"

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <filesystem>

#include "acquisition/capture_file.hpp"
#include "acquisition/contained_read.hpp"
#include "jobs/export/report_export.hpp"
#include "jobs/job_error.hpp"
#include "jobs/nominal_material.hpp"
#include "jobs/report/diagnosis_plot.hpp"
#include "update/gap_diagnosis.hpp"

namespace piezo::jobs {

namespace {

namespace fs = std::filesystem;

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
// description naming a preset, or none, is a warning: jobs/nominal_material.hpp).
std::string choose_material(const DiagnoseRequest& a, const acq::Capture& fit, std::vector<std::string>& warnings) {
  const auto nm = jobs::nominal_material(a.material, fit.setup.material);
  if (nm.warning) {
    if (a.warn) a.warn(*nm.warning);
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
std::string why_not_diagnosed(const jobs::PipelineResult& r) {
  std::string why = "the gap diagnosis did not run";
  for (const auto& s : r.stages)
    if (s.name == "diagnose" && !s.ran) why += ": " + s.note;
  for (const auto& s : r.stages)
    if (s.name == "update" && !s.ran) why += " (" + s.note + ")";
  return why;
}

// Which data the plot shows and which it was judged on (the held-out data as
// the diagnosis found them when no --holdout was given).
std::string plot_subtitle(const DiagnoseRequest& a, const std::string& material,
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

}  // namespace

DiagnoseResult run_diagnose(const DiagnoseRequest& a) {
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
  const std::string material = choose_material(a, fit_attrs, material_warnings);
  require_transient_shot(fit_attrs, a.fit);
  if (!a.holdout.empty()) require_transient_shot(capture_attributes(a.holdout), a.holdout);

  jobs::PipelineRequest req;
  req.replay_capture = a.fit;
  req.heldout_capture = a.holdout;
  req.material = material;
  req.isotropic = !a.transverse;
  req.gap_candidates = a.candidates;
  req.seed_chain = a.seed_chain;
  req.oe_options = a.oe;
  std::atomic<bool> cancel{false};
  DiagnoseResult out;
  out.material = material;
  jobs::PipelineResult& res = out.pipeline;
  try {
    res = jobs::run_pipeline(req, a.progress, cancel);
  } catch (const std::invalid_argument& e) {  // e.g. no transient dut shot to estimate Z from
    throw InputError(a.fit + ": " + e.what());
  }
  res.warnings.insert(res.warnings.begin(), material_warnings.begin(), material_warnings.end());
  if (!res.diagnosis) throw InputError(a.fit + ": " + why_not_diagnosed(res));
  const auto& d = *res.diagnosis;
  if (!a.holdout.empty() && d.n_heldout == 0)
    throw InputError(a.holdout +
                     ": fewer than 3 transient dut shots; the held-out data could not be used");

  if (!a.plot.empty()) {
    report::DiagnosisPlotOptions po;
    po.width = size.first;
    po.height = size.second;
    po.subtitle = plot_subtitle(a, material, d);
    report::write_diagnosis_png(d, po, a.plot);
    out.plot = a.plot;
  }
  return out;
}

nlohmann::json diagnose_json(const DiagnoseRequest& a, const DiagnoseResult& r) {
  const auto& res = r.pipeline;
  const std::string& plot = r.plot;
  nlohmann::json j = jobs::diagnosis_json(*res.diagnosis);
  // context fields; none of the names
  nlohmann::json c;
  c["capture"] = a.fit;
  c["holdout_capture"] = a.holdout.empty() ? nlohmann::json(nullptr) : nlohmann::json(a.holdout);
  c["material"] = r.material;
  c["material_class"] = a.transverse ? "transversely isotropic" : "isotropic";
  c["shots"] = res.shots;
  {  // the rows of the pipeline's report: updated (corrected when an effect was named) with sigma and status
    const nlohmann::json rep = report_json(res);
    c["parameters"] = rep["parameters"];
    c["corrected_for"] = rep["corrected_for"];
    c["work"] = rep["work"];  // FE modal solves, Prony decompositions, FFTs (issue 43)
  }
  c["stages"] = nlohmann::json::array();
  for (const auto& s : res.stages)
    c["stages"].push_back({{"name", s.name}, {"ran", s.ran}, {"note", s.note}});
  c["plot"] = plot.empty() ? nlohmann::json(nullptr) : nlohmann::json(plot);
  c["warnings"] = res.warnings;
  j.update(c);
  return j;
}

}  // namespace piezo::jobs
