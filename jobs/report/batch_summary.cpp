#include "jobs/report/batch_summary.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "jobs/report/markdown.hpp"

namespace piezo::jobs::report {

namespace fs = std::filesystem;

BatchEntry batch_entry(const std::string& key, const nlohmann::json& rec) {
  BatchEntry e;
  e.key = key;
  e.path = rec.value("path", "");
  e.sha256 = rec.value("sha256", "");
  e.status = rec.value("status", "failed");
  if (rec.contains("error") && rec["error"].is_object())
    e.error = rec["error"].value("message", "");
  if (!rec.contains("result") || !rec["result"].is_object()) return e;
  const auto& r = rec["result"];
  if (r.contains("verdict") && r["verdict"].is_string())
    e.verdict = r["verdict"].get<std::string>();
  if (r.contains("parameters") && r["parameters"].is_array())
    for (const auto& p : r["parameters"])
      if (p.contains("name") && p.contains("updated") && p["updated"].is_number())
        e.values.push_back(
            {p["name"].get<std::string>(), p.value("unit", ""), p["updated"].get<double>()});
  // Frequencies per identified mode (issue 41 item 3): the per-mode figures'
  // modes in order of frequency — the updated model's electrically active
  // modes, so "mode 2" is the same mode in every capture — a mode its own
  // status calls unreliable left out. The raw feature lists (whatever the
  // estimate found first) only where a capture has no mode figures.
  const bool modes = r.contains("modes") && r["modes"].is_array() && !r["modes"].empty();
  if (modes) {
    for (std::size_t k = 0; k < r["modes"].size() && k < 3; ++k) {
      const auto& m = r["modes"][k];
      if (!m.is_object() || m.value("status", std::string("ok")) != "ok") continue;
      for (const auto& [field, prefix] : {std::pair("fs_hz", "fs_mode"), std::pair("fp_hz", "fp_mode")})
        if (m.contains(field) && m[field].is_number())
          e.values.push_back({prefix + std::to_string(k + 1), "Hz", m[field].get<double>()});
    }
  } else {
    for (const auto& [field, prefix] :
         {std::pair("resonances_hz", "f_r"), std::pair("antiresonances_hz", "f_a")})
      if (r.contains(field) && r[field].is_array())
        for (std::size_t k = 0; k < r[field].size() && k < 3; ++k)
          if (r[field][k].is_number())
            e.values.push_back({prefix + std::to_string(k + 1) + " (estimate order)", "Hz", r[field][k].get<double>()});
  }
  return e;
}

const BatchEntry::Value* BatchEntry::find(const std::string& name) const {
  for (const auto& v : values)
    if (v.name == name) return &v;
  return nullptr;
}

BatchSummary summarize(std::vector<BatchEntry> entries) {
  BatchSummary s;
  std::sort(entries.begin(), entries.end(), [](const BatchEntry& a, const BatchEntry& b) {
    return a.path != b.path ? a.path < b.path : a.key < b.key;
  });
  s.entries = std::move(entries);
  for (const auto& e : s.entries) (e.status == "ok" ? s.ok : s.failed)++;
  // Quantities in order of first appearance (parameters, then features).
  std::vector<BatchEntry::Value> qs;
  for (const auto& e : s.entries)
    for (const auto& v : e.values)
      if (std::none_of(qs.begin(), qs.end(), [&](const auto& q) { return q.name == v.name; }))
        qs.push_back(v);
  std::stable_partition(qs.begin(), qs.end(),
                        [](const auto& q) { return q.unit != "Hz"; });
  for (const auto& q : qs) {
    Distribution d;
    d.name = q.name;
    d.unit = q.unit;
    std::vector<double> v;
    for (std::size_t i = 0; i < s.entries.size(); ++i) {
      const auto& e = s.entries[i];
      if (e.status != "ok") continue;
      const auto* x = e.find(q.name);
      if (!x || !std::isfinite(x->value)) continue;
      d.values.emplace_back(i, x->value);
      v.push_back(x->value);
    }
    d.stats = robust_stats(v);
    for (const auto& [i, x] : d.values)
      if (is_outlier(x, d.stats)) d.outliers.push_back(i);
    s.distributions.push_back(std::move(d));
  }
  return s;
}

std::string capture_report_folder(const std::string& path, const std::string& key) {
  // The folder it sits in, then its name ("05-fit" for refsim-v1/05/fit.h5: the
  // case or tube a lot's files are filed under), and the first 8 digits of
  // the record key (the same name in two places).
  const fs::path p(path);
  std::string stem = p.stem().string();
  const std::string parent = p.parent_path().filename().string();
  if (!parent.empty() && parent != "." && parent != "..") stem = parent + "-" + stem;
  for (char& c : stem)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.')) c = '_';
  if (stem.empty()) stem = "capture";
  return "captures/" + stem + "-" + key.substr(0, 8);
}

std::string batch_summary_markdown(const BatchSummary& s, const std::string& results_file) {
  std::ostringstream o;
  o << "# Replay batch summary\n\n"
    << "- results: `" << results_file << "`\n"
    << "- captures: " << s.entries.size() << " (" << s.ok << " replayed, " << s.failed
    << " failed)\n\n"
    << "## Distributions across transducers\n\n"
    << "Outliers: modified z-score 0.6745·|x − median| / MAD above "
    << fmt("%.1f", kOutlierThreshold) << " (Iglewicz & Hoaglin), with at least " << kMinForOutliers
    << " values.\n\n"
    << "| quantity | unit | n | median | MAD | min | max | outliers |\n| --- | --- | --- | --- | "
       "--- | --- | --- | --- |\n";
  for (const auto& d : s.distributions)
    o << "| " << d.name << " | " << d.unit << " | " << d.stats.n << " | "
      << fmt("%.6g", d.stats.median) << " | " << fmt("%.3g", d.stats.mad) << " | "
      << fmt("%.6g", d.stats.min) << " | " << fmt("%.6g", d.stats.max) << " | " << d.outliers.size()
      << " |\n";
  o << "\n![distributions](distributions.svg)\n";
  bool any = false;
  for (const auto& d : s.distributions)
    for (std::size_t i : d.outliers) {
      if (!any)
        o << "\n## Outliers\n\n| capture | quantity | value | median | modified z |\n| --- | --- | "
             "--- | --- | --- |\n";
      any = true;
      const auto& e = s.entries[i];
      const double x = e.find(d.name)->value;
      o << "| [" << cell(e.path) << "](" << capture_report_folder(e.path, e.key)
        << "/summary.md) | " << d.name << " | " << fmt("%.6g", x) << " | "
        << fmt("%.6g", d.stats.median) << " | " << fmt("%+.1f", modified_z(x, d.stats)) << " |\n";
    }
  if (!any) o << "\nNo outliers.\n";
  if (s.failed) {
    o << "\n## Failed captures (skipped)\n\n| capture | error |\n| --- | --- |\n";
    for (const auto& e : s.entries)
      if (e.status != "ok") o << "| " << cell(e.path) << " | " << cell(e.error) << " |\n";
  }
  o << "\n## Captures\n\n| capture | status |";
  for (const auto& d : s.distributions) o << " " << d.name << " |";
  o << " report |\n| --- | --- |";
  for (std::size_t k = 0; k < s.distributions.size(); ++k) o << " --- |";
  o << " --- |\n";
  for (const auto& e : s.entries) {
    o << "| " << cell(e.path) << " | " << e.status << " |";
    for (const auto& d : s.distributions) {
      const auto* x = e.find(d.name);
      o << " " << (x ? fmt("%.5g", x->value) : "-") << " |";
    }
    o << " [summary](" << capture_report_folder(e.path, e.key) << "/summary.md) |\n";
  }
  return o.str();
}

Figure distributions_figure(const BatchSummary& s) {
  Figure fig;
  fig.title = "Distributions across transducers (captures in path order; red: outliers)";
  fig.width = 900;
  fig.panel_height = 220;
  for (const auto& d : s.distributions) {
    Panel p;
    p.title = d.name;
    p.x_label = "capture";
    p.y_label = d.unit.empty() || d.unit == "-" ? d.name : d.name + " [" + d.unit + "]";
    p.x_range = std::pair(0.0, static_cast<double>(s.entries.size()) + 1.0);
    Series in{"", {}, {}, "#1f77b4", 2.5, false, true},
        out{"", {}, {}, "#d62728", 3.5, false, true};
    for (const auto& [i, x] : d.values) {
      const bool o = std::find(d.outliers.begin(), d.outliers.end(), i) != d.outliers.end();
      (o ? out : in).x.push_back(static_cast<double>(i) + 1.0);
      (o ? out : in).y.push_back(x);
    }
    p.series = {std::move(in), std::move(out)};
    if (d.stats.n) {
      p.hlines.push_back({d.stats.median, "#444444", false, "median"});
      if (d.stats.mad > 0 && d.stats.n >= kMinForOutliers) {  // the limits where the rule applies
        const double band = kOutlierThreshold * d.stats.mad / 0.6745;
        p.hlines.push_back({d.stats.median + band, "#d62728", true, "outlier limit"});
        p.hlines.push_back({d.stats.median - band, "#d62728", true, ""});
      }
    }
    fig.panels.push_back(std::move(p));
  }
  return fig;
}

void write_batch_report(const BatchSummary& s, const std::string& results_file,
                        const fs::path& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw std::runtime_error("report: cannot create " + dir.string() + ": " + ec.message());
  write_svg(distributions_figure(s), dir / "distributions.svg");
  const fs::path md = dir / "summary.md";
  std::ofstream f(md);
  if (!f || !(f << batch_summary_markdown(s, results_file)) || !f.flush())
    throw std::runtime_error("report: cannot write " + md.string());
}

}  // namespace piezo::jobs::report
