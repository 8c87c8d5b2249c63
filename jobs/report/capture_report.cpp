#include "jobs/report/capture_report.hpp"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "jobs/report/impedance_plot.hpp"
#include "jobs/report/mode_report.hpp"
#include "jobs/export/report_export.hpp"
#include "jobs/report/markdown.hpp"
#include "jobs/text/uncertain_text.hpp"
#include "jobs/text/user_message.hpp"

namespace piezo::jobs::report {

namespace fs = std::filesystem;

namespace {

void header(std::ostringstream& o, const CaptureInfo& info) {
  o << "# Replay of `" << info.input_path << "`\n\n"
    << "- SHA-256: `" << info.sha256 << "`\n";
  if (!info.material.empty()) o << "- nominal model: " << info.material << "\n";
  o << "- replay time: " << fmt("%.2f", info.elapsed_s) << " s\n";
}

void write_text(const fs::path& file, const std::string& s) {
  std::ofstream f(file);
  if (!f || !(f << s) || !f.flush())
    throw std::runtime_error("report: cannot write " + file.string());
}

void make_dir(const fs::path& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw std::runtime_error("report: cannot create " + dir.string() + ": " + ec.message());
}

}  // namespace

std::string capture_summary_markdown(const jobs::PipelineResult& r, const CaptureInfo& info) {
  std::ostringstream o;
  header(o, info);
  if (!info.limits_status.empty()) {
    o << "## " << info.limits_status << "\n\n";
    for (const auto& why : info.limits_reasons) o << "- " << cell(why) << "\n";
    if (!info.limits_reasons.empty()) o << "\n";
  }
  if (r.diagnosis) o << "- verdict: **" << cell(r.diagnosis->verdict_effect) << "**\n";
  o << "- shots: " << r.shots << " (" << r.shots_averaged
    << " averaged for the Prony-SS fit, order " << r.order << ")\n\n";
  if (!r.verdict.empty()) o << "**Gap verdict:** " << cell(r.verdict) << "\n\n";
  o << "## Stages\n\n| stage | ran | note |\n| --- | --- | --- |\n";
  for (const auto& s : r.stages)
    o << "| " << s.name << " | " << (s.ran ? "yes" : "no") << " | " << cell(user_message(s.note)) << " |\n";
  if (!r.params.empty()) {
    o << "\n## Parameters\n\nUpdate: " << r.update_method;
    if (r.corrected) o << "; **" << cell(r.corrected->label) << "** (the updated constants below are refitted with it)";
    o << "\n\n| parameter | unit | original | updated ± sigma | change | status | CMCM (seed) |"
      << (r.corrected ? " without the effect ± sigma | its status |" : "") << "\n"
      << "| --- | --- | --- | --- | --- | --- | --- |" << (r.corrected ? " --- | --- |" : "") << "\n";
    for (const auto& p : r.params) {  // σ to two significant digits, the value to match; "—" for no σ
      o << "| " << p.name << " | " << p.unit << " | " << fmt("%.6g", p.original) << " | "
        << format_uncertain(p.updated, p.sigma.value_or(NAN), {}, {true}) << " | "
        << (p.original != 0 ? fmt("%+.2f %%", 100.0 * (p.updated - p.original) / p.original) : "-")
        << " | " << cell(p.status) << " | " << (p.cmcm ? fmt("%.6g", *p.cmcm) : "-") << " |";
      if (r.corrected)
        o << " " << (p.uncorrected ? format_uncertain(*p.uncorrected, p.uncorrected_sigma.value_or(NAN), {}, {true}) : "-")
          << " | " << cell(p.uncorrected_status) << " |";
      o << "\n";
    }
    if (r.output_error && r.output_error->ok())
      o << "\ncorr(nu12, d31) " << format_value(r.output_error->corr_nu12_d31, {}, 3) << ", chi2/dof "
        << fmt("%.3g", r.output_error->chi2_per_dof) << " (limit "
        << fmt("%.3g", r.output_error->chi2_limit) << "), "
        << update::damping_summary(*r.output_error) << "\n";
  }
  o << "\n## Features (Prony-SS)\n\n";
  auto list = [&](const char* what, const std::vector<double>& v) {
    o << "- " << what << ": ";
    if (v.empty()) o << "none";
    for (std::size_t k = 0; k < v.size(); ++k) o << (k ? ", " : "") << fmt("%.1f", v[k]) << " Hz";
    o << "\n";
  };
  list("resonances", r.resonances_hz);
  list("anti-resonances", r.antiresonances_hz);
  if (!r.warnings.empty()) {
    o << "\n## Warnings\n\n";
    for (const auto& w : r.warnings) o << "- " << user_message(w) << "\n";
  }
  o << mode_figures_markdown(r);
  o << "\n## Impedance\n\n![|Z| and phase: measured, original and updated model](impedance.svg)\n\n"
    << "Exports: [impedance.csv](impedance.csv) (f_hz,re_ohm,im_ohm), "
       "[impedance.s1p](impedance.s1p) "
       "(Touchstone, Z, RI), [result.json](result.json) (parameters, features, stages).\n";
  return o.str();
}

std::string failed_capture_markdown(const CaptureInfo& info, const std::string& error) {
  std::ostringstream o;
  header(o, info);
  o << "\n**FAILED — skipped:** " << error << "\n";
  return o.str();
}

void write_capture_report(const jobs::PipelineResult& r, const CaptureInfo& info,
                          const fs::path& dir) {
  make_dir(dir);
  write_svg(impedance_figure(r, info.input_path), dir / "impedance.svg");
  if (const auto ny = nyquist_figure(r)) write_svg(*ny, dir / "nyquist.svg");
  if (!r.curves.empty()) {
    jobs::export_csv(r, (dir / "impedance.csv").string());
    jobs::export_touchstone(r, (dir / "impedance.s1p").string());
  }
  jobs::export_json(r, (dir / "result.json").string());
  write_text(dir / "summary.md", capture_summary_markdown(r, info));
}

void write_failed_capture_report(const CaptureInfo& info, const std::string& error,
                                 const fs::path& dir) {
  make_dir(dir);
  write_text(dir / "summary.md", failed_capture_markdown(info, error));
}

}  // namespace piezo::jobs::report
