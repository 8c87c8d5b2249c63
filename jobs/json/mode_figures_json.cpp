#include "jobs/json/mode_figures_json.hpp"

#include <cmath>
#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "jobs/text/uncertain_text.hpp"

namespace piezo::jobs {

namespace {

// A value and its σ under `name` / `sigma_name`.
void put(nlohmann::json& j, const char* name, const char* sigma_name, const dsp::Uncertain& u) {
  j[name] = u.value;
  j[sigma_name] = u.sigma;
}

double num(const nlohmann::json& j, const char* key) {
  return j.contains(key) && j[key].is_number() ? j[key].get<double>() : NAN;
}

// "value ± sigma" scaled (σ to two significant digits, jobs/text/uncertain_text.hpp),
// or the value by `f` and "± —" when σ is not finite, or "-" when the value is not.
std::string vs(const nlohmann::json& j, const char* key, const char* skey, double scale,
               const char* f) {
  const double v = num(j, key), s = num(j, skey);
  if (!std::isfinite(v)) return "-";
  if (std::isfinite(s) && s > 0) return format_uncertain(v * scale, s * scale, {}, {true});
  char buf[96];
  std::snprintf(buf, sizeof buf, f, v * scale);
  return std::string(buf) + (std::isfinite(s) ? "" : " ± —");
}

// `t` padded with spaces to `width` characters (UTF-8 continuation bytes not counted).
std::string pad(const std::string& t, int width) {
  int chars = 0;
  for (unsigned char c : t) chars += (c & 0xC0) != 0x80;
  return t + std::string(static_cast<std::size_t>(std::max(0, width - chars)), ' ');
}

}  // namespace

nlohmann::json modes_json(const dsp::ModeFiguresResult& r) {
  nlohmann::json a = nlohmann::json::array();
  for (const auto& m : r.modes) {
    nlohmann::json j;
    put(j, "fs_hz", "fs_sigma_hz", m.fs_hz);
    put(j, "fp_hz", "fp_sigma_hz", m.fp_hz);
    put(j, "fm_hz", "fm_sigma_hz", m.fm_hz);
    put(j, "fn_hz", "fn_sigma_hz", m.fn_hz);
    put(j, "k_eff", "k_eff_sigma", m.k_eff);
    put(j, "k_eff2", "k_eff2_sigma", m.k_eff2);
    put(j, "qm_branch", "qm_branch_sigma", m.qm_branch);
    put(j, "qm_bandwidth", "qm_bandwidth_sigma", m.qm_bandwidth);
    j["f1_hz"] = m.conductance.f1_hz;
    j["f2_hz"] = m.conductance.f2_hz;
    j["fs_conductance_hz"] = m.conductance.fs_hz;
    put(j, "r1_ohm", "r1_sigma_ohm", m.r1_ohm);
    put(j, "l1_h", "l1_sigma_h", m.l1_h);
    put(j, "c1_f", "c1_sigma_f", m.c1_f);
    put(j, "c0_f", "c0_sigma_f", m.c0_f);
    put(j, "frequency_constant_hz_m", "frequency_constant_sigma_hz_m", m.frequency_constant_hz_m);
    j["fit"] = {{"points", m.fit.points},
                {"window_lo_hz", m.window_lo_hz},
                {"window_hi_hz", m.window_hi_hz},
                {"converged", m.fit.converged},
                {"weighted", m.fit.weighted},
                {"chi2_per_dof", m.fit.chi2_per_dof},
                {"rms_rel_residual", m.fit.rms_rel_residual},
                {"iterations", m.fit.iterations}};
    j["notes"] = m.notes;
    j["status"] = m.status;
    j["reasons"] = m.reasons;
    a.push_back(j);
  }
  return a;
}

nlohmann::json mode_summary_json(const dsp::ModeFiguresResult& r, double d_mean,
                                 const std::string& source) {
  nlohmann::json j;
  put(j, "free_capacitance_f", "free_capacitance_sigma_f", r.free_capacitance_f);
  put(j, "tan_delta", "tan_delta_sigma", r.tan_delta);
  j["reference_hz"] = r.reference_used_hz;
  j["hoop_mode"] = r.hoop_mode;
  j["mean_diameter_m"] = d_mean;
  j["mean_diameter_source"] = source;
  put(j, "frequency_constant_hz_m", "frequency_constant_sigma_hz_m", r.frequency_constant_hz_m);
  j["sweeps"] = r.sweeps;
  j["notes"] = r.notes;
  return j;
}

void print_mode_figures(std::FILE* out, const nlohmann::json& modes, const nlohmann::json& s) {
  std::fprintf(out, "  mode figures (IEEE 176 / EN 50324-2; %s, ±1σ)\n",
               s.contains("source") && s["source"].is_string() ? s["source"].get<std::string>().c_str()
                                                               : "BVD fit per mode");
  // Columns padded by characters, not bytes ("±" is two bytes in UTF-8).
  static const int kWidth[] = {3, 20, 20, 19, 16, 16, 16, 19, 19, 17};
  auto row = [&](const std::vector<std::string>& cells) {
    std::string line = " ";
    for (std::size_t c = 0; c < cells.size(); ++c) line.append(" ").append(pad(cells[c], kWidth[c]));
    while (!line.empty() && line.back() == ' ') line.pop_back();
    std::fprintf(out, "%s\n", line.c_str());
  };
  row({"#", "fs [Hz]", "fp [Hz]", "k_eff", "Qm (R1 C1)", "Qm (fs/df)", "R1 [ohm]", "L1 [mH]", "C1 [pF]", "C0 [pF]"});
  for (std::size_t k = 0; k < modes.size(); ++k) {
    const auto& m = modes[k];
    row({std::to_string(k + 1), vs(m, "fs_hz", "fs_sigma_hz", 1, "%.2f"), vs(m, "fp_hz", "fp_sigma_hz", 1, "%.2f"),
         vs(m, "k_eff", "k_eff_sigma", 1, "%.4f"), vs(m, "qm_branch", "qm_branch_sigma", 1, "%.1f"),
         vs(m, "qm_bandwidth", "qm_bandwidth_sigma", 1, "%.1f"), vs(m, "r1_ohm", "r1_sigma_ohm", 1, "%.3g"),
         vs(m, "l1_h", "l1_sigma_h", 1e3, "%.4g"), vs(m, "c1_f", "c1_sigma_f", 1e12, "%.4g"),
         vs(m, "c0_f", "c0_sigma_f", 1e12, "%.4g")});
    std::fprintf(
        out, "      fm %s Hz, fn %s Hz, N = fs*D_mean %s Hz*m\n",
        vs(m, "fm_hz", "fm_sigma_hz", 1, "%.2f").c_str(),
        vs(m, "fn_hz", "fn_sigma_hz", 1, "%.2f").c_str(),
        vs(m, "frequency_constant_hz_m", "frequency_constant_sigma_hz_m", 1, "%.1f").c_str());
    if (m.contains("reasons"))
      for (const auto& r : m["reasons"]) std::fprintf(out, "      UNRELIABLE: %s\n", r.get<std::string>().c_str());
    for (const auto& n : m["notes"])
      std::fprintf(out, "      note: %s\n", n.get<std::string>().c_str());
  }
  if (s.contains("reference_hz"))
    std::fprintf(out, "  C^T %s pF, tan delta %s at %.6g Hz\n",
                 vs(s, "free_capacitance_f", "free_capacitance_sigma_f", 1e12, "%.5g").c_str(),
                 vs(s, "tan_delta", "tan_delta_sigma", 1, "%.3g").c_str(), num(s, "reference_hz"));
  if (s.contains("hoop_mode") && s["hoop_mode"].get<int>() >= 0)
    std::fprintf(
        out, "  hoop mode %d (most strongly coupled): N = %s Hz*m (D_mean %.5g m, %s)\n",
        s["hoop_mode"].get<int>() + 1,
        vs(s, "frequency_constant_hz_m", "frequency_constant_sigma_hz_m", 1, "%.1f").c_str(),
        num(s, "mean_diameter_m"), s["mean_diameter_source"].get<std::string>().c_str());
  if (s.contains("notes"))
    for (const auto& n : s["notes"])
      std::fprintf(out, "  note: %s\n", n.get<std::string>().c_str());
}

}  // namespace piezo::jobs
