#include "jobs/report/mode_report.hpp"

#include <cmath>
#include <sstream>

#include "jobs/mode_nyquist.hpp"
#include "jobs/report/markdown.hpp"
#include "jobs/text/uncertain_text.hpp"

namespace piezo::jobs::report {

namespace {

// σ to two significant digits, the value to match (jobs/text/uncertain_text.hpp);
// the value by `f` and "± —" when σ is not finite, by `f` alone when it is 0.
std::string pm(const dsp::Uncertain& u, double scale, const char* f) {
  if (!std::isfinite(u.value)) return "-";
  if (std::isfinite(u.sigma) && u.sigma > 0) return format_uncertain(u.value * scale, u.sigma * scale, {}, {true});
  return fmt(f, u.value * scale) + (std::isfinite(u.sigma) ? "" : " ± —");
}

const jobs::Curve* estimate_curve(const jobs::PipelineResult& r) {
  for (const auto& c : r.curves)
    if (c.label == "measured (Prony-SS)") return &c;  // the estimate the figures were computed on
  return nullptr;
}

}  // namespace

std::string mode_figures_markdown(const jobs::PipelineResult& r) {
  std::ostringstream o;
  o << "\n## Per-mode figures";
  if (r.mode_figures && !r.mode_figures->source.empty()) o << " (" << r.mode_figures->source << ")";
  o << "\n\n";
  if (!r.mode_figures) {
    o << "None: no impedance estimate.\n";
    return o.str();
  }
  if (!r.mode_figures->error.empty()) {
    o << "None: " << cell(r.mode_figures->error) << "\n";
    return o.str();
  }
  const auto& f = r.mode_figures->figures;
  o << "IEEE Std 176 / EN 50324-2: fs, fp of the motional branch, k_eff² = (fp² − fs²)/fp², Qm from the branch "
       "(1/(2π fs R1 C1)) and from the conductance's 3-dB width; the BVD branch R1, L1, C1 beside C0.\n\n"
    << "| mode | fs [kHz] | fp [kHz] | k_eff | Qm (branch) | Qm (3 dB) | R1 [Ω] | L1 [mH] | C1 [pF] | C0 [nF] |\n"
       "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n";
  for (std::size_t i = 0; i < f.modes.size(); ++i) {
    const auto& m = f.modes[i];
    o << "| " << i + 1 << (static_cast<int>(i) == f.hoop_mode ? " (hoop)" : "") << " | " << pm(m.fs_hz, 1e-3, "%.4f")
      << " | " << pm(m.fp_hz, 1e-3, "%.4f") << " | " << pm(m.k_eff, 1.0, "%.4f") << " | "
      << pm(m.qm_branch, 1.0, "%.4g") << " | " << pm(m.qm_bandwidth, 1.0, "%.4g") << " | "
      << pm(m.r1_ohm, 1.0, "%.4g") << " | " << pm(m.l1_h, 1e3, "%.4g") << " | " << pm(m.c1_f, 1e12, "%.4g")
      << " | " << pm(m.c0_f, 1e9, "%.4g") << " |\n";
  }
  o << "\nFree capacitance C^T " << pm(f.free_capacitance_f, 1e9, "%.5g") << " nF and tan δ "
    << pm(f.tan_delta, 1.0, "%.3g") << " at " << fmt("%.0f", f.reference_used_hz) << " Hz; frequency constant N "
    << pm(f.frequency_constant_hz_m, 1.0, "%.5g") << " Hz·m (hoop mode, D_mean from "
    << r.mode_figures->mean_diameter_source << ").\n";
  if (nyquist_figure(r)) o << "\n![admittance plane of each mode](nyquist.svg)\n";
  return o.str();
}

std::optional<Figure> nyquist_figure(const jobs::PipelineResult& r, int max_modes) {
  const jobs::Curve* c = estimate_curve(r);
  if (!c || !r.mode_figures || !r.mode_figures->error.empty()) return std::nullopt;
  const auto ny = jobs::mode_nyquist(c->f_hz, c->z_ohm, r.mode_figures->figures);
  if (ny.empty()) return std::nullopt;
  Figure fig;
  const bool model = r.mode_figures->source.rfind("updated FE model", 0) == 0;
  fig.title = model ? "Admittance plane per mode: the estimate, the updated model's branch, the motional circle"
                    : "Admittance plane per mode: the estimate, the fitted BVD network, the motional circle";
  fig.width = 700;
  fig.panel_height = 420;
  auto ms = [](const std::vector<double>& v) {
    std::vector<double> o(v.size());
    for (std::size_t i = 0; i < v.size(); ++i) o[i] = 1e3 * v[i];
    return o;
  };
  for (const auto& n : ny) {
    if (static_cast<int>(fig.panels.size()) >= max_modes) break;
    Panel p;
    p.title = "mode " + std::to_string(n.mode + 1) + ", fs " + fmt("%.3f", n.fs_hz / 1e3) + " kHz";
    p.x_label = "G [mS]";
    p.y_label = "B [mS]";
    p.series.push_back({"motional circle", ms(n.circle_g_s), ms(n.circle_b_s), "#999999", 1.0, true, false});
    p.series.push_back({model ? "updated model" : "fitted BVD", ms(n.fit_g_s), ms(n.fit_b_s), "#2ca02c", 2.0, false, false});
    p.series.push_back({"measured (Prony-SS)", ms(n.g_s), ms(n.b_s), "#ff7f0e", 1.0, false, true});
    fig.panels.push_back(std::move(p));
  }
  return fig;
}

}  // namespace piezo::jobs::report
