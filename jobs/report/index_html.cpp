// report/index.html of a replay (index_html.hpp).
#include "jobs/report/index_html.hpp"

#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "jobs/report/batch_summary.hpp"
#include "jobs/text/uncertain_text.hpp"

namespace piezo::jobs::report {

namespace fs = std::filesystem;

namespace {

std::string esc(const std::string& s) {
  std::string o;
  o.reserve(s.size());
  for (char c : s) switch (c) {
      case '&': o += "&amp;"; break;
      case '<': o += "&lt;"; break;
      case '>': o += "&gt;"; break;
      case '"': o += "&quot;"; break;
      default: o += c;
    }
  return o;
}

// An SVG file of the report, inline (its XML prolog dropped); empty if absent.
// Its ids (Cairo's glyph0-1, clip1, ...) are prefixed, so that two figures on
// the page do not resolve each other's glyphs and clip paths.
std::string inline_svg(const fs::path& file, const std::string& prefix) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return {};
  std::ostringstream t;
  t << in.rdbuf();
  const std::string s = t.str();
  const auto p = s.find("<svg");
  if (p == std::string::npos) return {};
  std::string out;
  out.reserve(s.size() - p + 1024);
  for (std::size_t i = p; i < s.size();) {
    bool hit = false;
    for (const char* ref : {"id=\"", "href=\"#", "url(#"})
      if (s.compare(i, std::strlen(ref), ref) == 0) {
        out += ref + prefix;
        i += std::strlen(ref);
        hit = true;
        break;
      }
    if (!hit) out += s[i++];
  }
  return out;
}

std::string str(const nlohmann::json& j, const char* key) {
  return j.is_object() && j.contains(key) && j[key].is_string() ? j[key].get<std::string>() : std::string();
}

}  // namespace

std::string index_html(const std::vector<std::pair<std::string, nlohmann::json>>& records,
                       const std::string& results_file, const fs::path& report_dir) {
  std::size_t pass = 0, fail = 0, error = 0, judged = 0, ok = 0;
  for (const auto& [key, rec] : records) {
    ok += str(rec, "status") == "ok";
    if (!rec.contains("limits") || !rec["limits"].is_object()) continue;
    ++judged;
    const std::string st = str(rec["limits"], "status");
    (st == "pass" ? pass : st == "fail" ? fail : error)++;
  }
  std::ostringstream o;
  o << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>piezobench replay report</title>\n"
       "<style>body{font-family:sans-serif;margin:1.5em;max-width:1400px}"
       "table{border-collapse:collapse;font-size:13px}td,th{border:1px solid #ccc;padding:3px 6px;vertical-align:top}"
       "th{background:#eee}.pass{background:#2e7d32;color:#fff;font-weight:bold}"
       ".fail{background:#c62828;color:#fff;font-weight:bold}.error{background:#6d4c41;color:#fff}"
       ".banner{font-size:22px;padding:8px 14px;display:inline-block;margin:4px 8px 4px 0}"
       ".muted{color:#777}.ni{color:#c66}svg{max-width:100%;height:auto}</style></head><body>\n";
  o << "<h1>Replay report</h1>\n<p>Results file <code>" << esc(results_file) << "</code>: " << records.size()
    << " capture(s), " << ok << " replayed, " << records.size() - ok << " failed. Markdown: "
    << "<a href=\"summary.md\">summary.md</a>"
    << (fs::exists(report_dir / "lot.md") ? ", <a href=\"lot.md\">lot.md</a>" : "") << ".</p>\n";
  if (judged) {
    o << "<div><span class=\"banner pass\">PASS " << pass << "</span><span class=\"banner fail\">FAIL " << fail
      << "</span>";
    if (error) o << "<span class=\"banner error\">ERROR " << error << "</span>";
    o << "</div>\n";
  } else {
    o << "<p class=\"banner error\">No limits loaded: nothing passed or failed (replay --limits FILE.toml)</p>\n";
  }
  o << "<h2>Captures</h2>\n<table><tr><th>capture</th><th>limits</th><th>verdict</th><th>constants "
       "(updated ± σ, status)</th><th>plots</th></tr>\n";
  for (const auto& [key, rec] : records) {
    const std::string path = str(rec, "path");
    const std::string folder = capture_report_folder(path, key);
    o << "<tr><td><a href=\"" << esc(folder) << "/summary.md\">" << esc(path) << "</a></td>";
    if (rec.contains("limits") && rec["limits"].is_object()) {
      const std::string st = str(rec["limits"], "status");
      o << "<td><span class=\"" << (st == "pass" ? "pass" : st == "fail" ? "fail" : "error") << "\">"
        << (st == "pass" ? "PASS" : st == "fail" ? "FAIL" : "ERROR") << "</span>";
      if (rec["limits"].contains("reasons") && rec["limits"]["reasons"].is_array())
        for (const auto& why : rec["limits"]["reasons"])
          if (why.is_string()) o << "<br><small>" << esc(why.get<std::string>()) << "</small>";
      o << "</td>";
    } else {
      o << "<td class=\"muted\">no limits</td>";
    }
    if (str(rec, "status") != "ok" || !rec.contains("result")) {
      std::string msg = rec.contains("error") ? str(rec["error"], "message") : std::string();
      o << "<td colspan=\"3\" class=\"ni\">failed: " << esc(msg) << "</td></tr>\n";
      continue;
    }
    const auto& r = rec["result"];
    const std::string verdict = r.contains("diagnosis") && r["diagnosis"].is_object()
                                    ? str(r["diagnosis"], "verdict_effect")
                                    : std::string();
    o << "<td>" << esc(verdict.empty() ? "-" : verdict) << "</td><td>";
    if (r.contains("corrected_for") && r["corrected_for"].is_object())
      o << "<b>" << esc(str(r["corrected_for"], "label")) << "</b><br>";
    if (r.contains("parameters") && r["parameters"].is_array())
      for (const auto& p : r["parameters"]) {
        const double v = p.value("updated", NAN);
        const double s = p.contains("sigma") && p["sigma"].is_number() ? p["sigma"].get<double>() : NAN;
        const std::string st = str(p, "status");
        o << esc(str(p, "name")) << " " << esc(format_uncertain(v, s, {}, {true})) << " "
          << "<span class=\"" << (st.rfind("ok", 0) == 0 ? "muted" : "ni") << "\">" << esc(st) << "</span><br>";
      }
    o << "</td><td><a href=\"" << esc(folder) << "/impedance.svg\">|Z|</a>";
    if (fs::exists(report_dir / folder / "nyquist.svg"))
      o << " · <a href=\"" << esc(folder) << "/nyquist.svg\">admittance plane</a>";
    o << "</td></tr>\n";
  }
  o << "</table>\n";
  for (const auto& [file, title] : {std::pair("lot_histograms.svg", "Lot histograms against the limits"),
                                    std::pair("distributions.svg", "Distributions across transducers")}) {
    const std::string svg = inline_svg(report_dir / file, fs::path(file).stem().string() + "-");
    if (!svg.empty()) o << "<h2>" << title << "</h2>\n" << svg << "\n";
  }
  o << "</body></html>\n";
  return o.str();
}

void write_index_html(const std::vector<std::pair<std::string, nlohmann::json>>& records,
                      const std::string& results_file, const fs::path& report_dir) {
  const fs::path file = report_dir / "index.html";
  std::ofstream f(file, std::ios::binary);
  const std::string s = index_html(records, results_file, report_dir);
  if (!f || !(f << s) || !f.flush()) throw std::runtime_error("report: cannot write " + file.string());
}

}  // namespace piezo::jobs::report
