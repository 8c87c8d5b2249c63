// Plots: |Z| (log–log) over frequency — measured vs original model vs updated
// model, with resonance / anti-resonance markers and the FFT and cross-spectra
// estimates as optional overlays — then the gap diagnosis' residual with its
// regions shaded, the phase, and the Hankel singular values with the chosen
// order.
#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>

#include "jobs/text/uncertain_text.hpp"
#include "ui/gui/residual_plot.hpp"
#include "ui/gui/windows.hpp"

namespace piezo::gui {

namespace {
std::string khz(double f) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3f kHz", f / 1e3);
  return b;
}

// Measured curves by their estimator's key (acquisition/estimators/), models by label.
ImU32 colour_for(const jobs::Curve& c) {
  if (c.label.find("original") != std::string::npos) return kColOriginal;
  if (c.label.find("updated") != std::string::npos) return kColUpdated;
  if (c.estimator == "fft") return kColFft;
  if (c.estimator == "xspec") return kColXspec;
  return kColMeasured;
}

void impedance_specs(const AppState& s, PlotSpec& mag, PlotSpec& ph) {
  if (!s.result) return;
  // Draw order: models first (the updated one wide, as a halo), the
  // measurement last and thin on top, so curves that agree stay visible.
  std::vector<const jobs::Curve*> order;
  for (const auto& c : s.result->curves)
    if (c.label.find("model") != std::string::npos) order.push_back(&c);
  for (const auto& c : s.result->curves)
    if (c.label.find("model") == std::string::npos) order.push_back(&c);
  for (const jobs::Curve* cp : order) {
    const auto& c = *cp;
    if (c.estimator == "fft" && !s.show_fft) continue;
    if (c.estimator == "xspec" && !s.show_xspec) continue;
    const double width = c.label.find("updated") != std::string::npos ? 6.0 : 2.0;
    Series m{c.label, c.f_hz, {}, colour_of(colour_for(c)), width};
    Series p = m;
    for (const auto& z : c.z_ohm) {
      m.y.push_back(std::abs(z));
      p.y.push_back(std::arg(z) * 180.0 / M_PI);
    }
    // The marker read-out: |Z|, phase, R and X of the curve there.
    m.readout = [z = c.z_ohm](std::size_t i) { return impedance_readout(z[i]); };
    mag.series.push_back(std::move(m));
    ph.series.push_back(std::move(p));
  }
  // The read-out snaps to the estimate's resonances and anti-resonances.
  for (double f : s.result->resonances_hz)
    mag.markers.push_back({f, {255, 255, 255, 90}, "resonance fr " + khz(f), true});
  for (double f : s.result->antiresonances_hz)
    mag.markers.push_back({f, {255, 160, 160, 90}, "anti-resonance fa " + khz(f), true});
  // Open on the resonance band (issue 41 item 5): from 0.8 x the lowest
  // resonance to 1.25 x the highest anti-resonance, so the modes fill the
  // plot instead of its right tenth; a double-click shows the whole estimate.
  double lo = INFINITY, hi = 0;
  for (double f : s.result->resonances_hz) lo = std::min(lo, f), hi = std::max(hi, f);
  for (double f : s.result->antiresonances_hz) lo = std::min(lo, f), hi = std::max(hi, f);
  if (hi > lo && lo > 0) {
    mag.fit_x0 = ph.fit_x0 = 0.8 * lo;
    mag.fit_x1 = ph.fit_x1 = 1.25 * hi;
  }
}
std::string pm(const dsp::Uncertain& u, double scale, const char* f) {
  if (!std::isfinite(u.value)) return "-";
  char b[64];
  std::snprintf(b, sizeof b, f, u.value * scale);
  std::string out = b;
  if (std::isfinite(u.sigma)) {
    std::snprintf(b, sizeof b, f, u.sigma * scale);
    out += std::string(" +- ") + b;
  }
  return out;
}

// A table cell: the value; its sigma on hover.
void cell(const dsp::Uncertain& u, double scale, const char* f) {
  ImGui::TableNextColumn();
  if (!std::isfinite(u.value)) {
    ImGui::TextDisabled("-");
    return;
  }
  char b[48];
  std::snprintf(b, sizeof b, f, u.value * scale);
  ImGui::TextUnformatted(b);
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", pm(u, scale, "%.4g").c_str());
}

// The per-mode figures as a table (a row selects the mode of the admittance
// plot beside it) and that mode's admittance plane: the estimate's points in
// the fit window, the fitted network and the motional circle.
void render_modes_row(AppState& s, float width, float height) {
  PlotSpec ny{.title = "admittance (mode)", .x_label = "G [mS]", .y_label = "B [mS]"};
  if (!s.nyquist.empty()) {
    s.nyquist_mode = std::clamp(s.nyquist_mode, 0, static_cast<int>(s.nyquist.size()) - 1);
    const auto& n = s.nyquist[static_cast<std::size_t>(s.nyquist_mode)];
    char t[96];
    std::snprintf(t, sizeof t, "admittance, mode %d (fs %.3f kHz)", n.mode + 1, n.fs_hz / 1e3);
    ny.title = t;
    auto ms = [](const std::vector<double>& v) {
      std::vector<double> o(v.size());
      for (std::size_t i = 0; i < v.size(); ++i) o[i] = 1e3 * v[i];
      return o;
    };
    ny.series.push_back({"motional circle", ms(n.circle_g_s), ms(n.circle_b_s), {255, 255, 255, 110}, 1.0});
    ny.series.push_back({"fitted BVD", ms(n.fit_g_s), ms(n.fit_b_s), colour_of(kColUpdated), 2.0});
    ny.series.push_back({"measured (Prony-SS)", ms(n.g_s), ms(n.b_s), colour_of(kColMeasured), 1.0, false, true});
  }
  // (G does not rise with frequency: these series stay out of the hover read-out.)
  plot("nyquist", ny, s.nyquist_view, ImVec2(width * 0.42f, height));
  ImGui::SameLine();
  ImGui::BeginChild("modes_table", ImVec2(0, height), true);
  if (!s.result || !s.result->mode_figures) {
    ImGui::TextDisabled("no per-mode figures (no impedance estimate)");
  } else if (!s.result->mode_figures->error.empty()) {
    ImGui::TextWrapped("no per-mode figures: %s", s.result->mode_figures->error.c_str());
  } else {
    const auto& r = s.result->mode_figures->figures;
    if (!s.result->mode_figures->source.empty()) ImGui::TextDisabled("%s", s.result->mode_figures->source.c_str());
    // σ to two significant digits, the value to match (dsp/uncertain_text.hpp).
    // (ImGui's font has no sigma: the words say it.)
    const dsp::UncertainStyle ascii{false, 3, "sigma not identifiable", "-"};
    const std::string head = "C^T " + jobs::format_si(r.free_capacitance_f.value, r.free_capacitance_f.sigma, "F", ascii) +
                             ", tan d " + jobs::format_uncertain(r.tan_delta.value, r.tan_delta.sigma, {}, ascii) + " at " +
                             jobs::format_value(r.reference_used_hz, "Hz", 4) + "; N " +
                             jobs::format_uncertain(r.frequency_constant_hz_m.value, r.frequency_constant_hz_m.sigma,
                                                    "Hz m", ascii) +
                             " (hoop mode); hover a value for its sigma";
    ImGui::TextWrapped("%s", head.c_str());
    // Columns at their content's width; the table scrolls sideways rather
    // than cutting L1 and C1 off at 1280 x 800 (issue 41 item 5).
    const ImGuiTableFlags flags = ImGuiTableFlags_Borders | ImGuiTableFlags_RowBg | ImGuiTableFlags_ScrollY |
                                  ImGuiTableFlags_ScrollX | ImGuiTableFlags_SizingFixedFit;
    if (ImGui::BeginTable("modes", 10, flags)) {
      for (const char* h : {"mode", "status", "fs kHz", "fp kHz", "k_eff", "Qm branch", "Qm 3 dB", "R1 ohm", "L1 mH", "C1 pF"})
        ImGui::TableSetupColumn(h);
      ImGui::TableSetupScrollFreeze(0, 1);
      ImGui::TableHeadersRow();
      for (std::size_t i = 0; i < r.modes.size(); ++i) {
        const auto& m = r.modes[i];
        ImGui::TableNextRow();
        ImGui::TableNextColumn();
        int ny_index = -1;
        for (std::size_t k = 0; k < s.nyquist.size(); ++k)
          if (s.nyquist[k].mode == static_cast<int>(i)) ny_index = static_cast<int>(k);
        char lab[32];
        std::snprintf(lab, sizeof lab, "%zu%s", i + 1, static_cast<int>(i) == r.hoop_mode ? " (hoop)" : "");
        if (ImGui::Selectable(lab, ny_index >= 0 && ny_index == s.nyquist_mode, ImGuiSelectableFlags_SpanAllColumns) &&
            ny_index >= 0) {
          s.nyquist_mode = ny_index;
          s.nyquist_view.fitted = false;
        }
        ImGui::TableNextColumn();
        if (m.status == "ok") {
          ImGui::TextUnformatted("ok");
        } else {
          ImGui::TextColored(ImVec4(1.0f, 0.45f, 0.35f, 1.0f), "%s", m.status.c_str());
          if (ImGui::IsItemHovered()) {
            std::string why;
            for (const auto& r : m.reasons) why += (why.empty() ? "" : "\n") + r;
            ImGui::SetTooltip("%s", why.c_str());
          }
        }
        cell(m.fs_hz, 1e-3, "%.4f");
        cell(m.fp_hz, 1e-3, "%.4f");
        cell(m.k_eff, 1.0, "%.4f");
        cell(m.qm_branch, 1.0, "%.4g");
        cell(m.qm_bandwidth, 1.0, "%.4g");
        cell(m.r1_ohm, 1.0, "%.4g");
        cell(m.l1_h, 1e3, "%.4g");
        cell(m.c1_f, 1e12, "%.4g");
      }
      ImGui::EndTable();
    }
  }
  ImGui::EndChild();
}
}  // namespace

void render_plots_window(AppState& s) {
  ImGui::Begin("Plots");
  ImGui::Checkbox("FFT overlay", &s.show_fft);
  ImGui::SameLine();
  ImGui::Checkbox("Cross-spectra overlay", &s.show_xspec);
  ImGui::SameLine();
  if (ImGui::Checkbox("Residual phase", &s.residual_phase)) s.residual_view.fitted = false;
  ImGui::SameLine();
  if (ImGui::Checkbox("log f", &s.residual_log_f)) s.residual_view.fitted = false;
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("Logarithmic frequency axis for the residual plot");
  ImGui::SameLine();
  tracked_checkbox(s, "Modes", &s.show_modes);
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip("Per-mode figures (IEEE 176 / EN 50324-2) and the admittance circle of each mode");
  ImGui::SameLine();
  if (ImGui::Button("Fit views"))
    s.mag_view.fitted = s.phase_view.fitted = s.sv_view.fitted = s.residual_view.fitted = s.nyquist_view.fitted =
        false;
  // Log frequency for the impedance; linear for the residual (unless asked),
  // whose regions crowd around the resonances in the top octave.
  PlotSpec mag{.title = "|Z|", .x_label = "f [Hz]", .y_label = "ohm", .x_scale = Scale::Log, .y_scale = Scale::Log};
  PlotSpec ph{.title = "phase", .x_label = "f [Hz]", .y_label = "deg", .x_scale = Scale::Log};
  impedance_specs(s, mag, ph);
  PlotSpec res{.title = "gap: residual (no diagnosis)", .x_label = "f [kHz]", .y_label = "dB"};
  if (s.result && s.result->diagnosis)
    res = residual_plot_spec(*s.result->diagnosis, s.residual_phase);
  res.x_scale = s.residual_log_f ? Scale::Log : Scale::Linear;
  PlotSpec sv{.title = "Hankel SVs", .x_label = "index", .y_label = "s_k/s_1", .y_scale = Scale::Log};
  if (s.result && !s.result->singular_values.empty()) {
    sv.title = "Hankel SVs (order " + std::to_string(s.result->order) + ")";
    Series pts{"s_k/s_1", {}, s.result->singular_values, colour_of(kColMeasured), 1.0, false, true};
    for (std::size_t i = 0; i < pts.y.size(); ++i) pts.x.push_back(static_cast<double>(i + 1));
    sv.series.push_back(std::move(pts));
    sv.markers.push_back({s.result->order + 0.5, {255, 80, 80, 200}});
    sv.bands.push_back({0.5, s.result->order + 0.5, {255, 80, 80, 30}, "", "",
                        "kept by Prony-SS (order " + std::to_string(s.result->order) + ")"});
  }

  // |Z| across the full width; below it the residual and the phase (the
  // singular values on a tab).
  const ImVec2 avail = ImGui::GetContentRegionAvail();
  const float row2 = avail.y * 0.52f;
  plot("mag", mag, s.mag_view, ImVec2(avail.x, avail.y - row2 - ImGui::GetStyle().ItemSpacing.y));
  if (s.show_modes) {
    render_modes_row(s, avail.x, row2);
    ImGui::End();
    return;
  }
  // The residual and the phase side by side; Prony's Hankel singular values
  // (how the order was chosen: for the engineer, not the technician) behind
  // a tab of their own.
  if (ImGui::BeginTabBar("lower")) {
    if (ImGui::BeginTabItem("Residual and phase")) {
      const float h = ImGui::GetContentRegionAvail().y;
      plot("residual", res, s.residual_view, ImVec2(avail.x * 0.58f, h));
      ImGui::SameLine();
      plot("phase", ph, s.phase_view, ImVec2(0, h));
      ImGui::EndTabItem();
    }
    if (ImGui::BeginTabItem("Hankel SVs")) {
      plot("sv", sv, s.sv_view, ImVec2(0, ImGui::GetContentRegionAvail().y));
      ImGui::EndTabItem();
    }
    ImGui::EndTabBar();
  }
  ImGui::End();
}

}  // namespace piezo::gui
