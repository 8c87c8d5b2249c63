// Plots: |Z| (log–log) over frequency — measured vs original model vs updated
// model, with resonance / anti-resonance markers and the FFT and cross-spectra
// estimates as optional overlays — then the gap diagnosis' residual with its
// regions shaded, the phase, and the Hankel singular values with the chosen
// order.
#include <cmath>
#include <complex>
#include <cstdio>

#include "ui/gui/residual_plot.hpp"
#include "ui/gui/windows.hpp"

namespace piezo::gui {

namespace {
std::string khz(double f) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3f kHz", f / 1e3);
  return b;
}

ImU32 colour_for(const std::string& label) {
  if (label.find("original") != std::string::npos) return kColOriginal;
  if (label.find("updated") != std::string::npos) return kColUpdated;
  if (label.find("FFT") != std::string::npos) return kColFft;
  if (label.find("cross") != std::string::npos) return kColXspec;
  return kColMeasured;
}

void impedance_specs(const AppState& s, PlotSpec& mag, PlotSpec& ph) {
  if (!s.result) return;
  // Draw order: models first (the updated one wide, as a halo), the
  // measurement last and thin on top, so curves that agree stay visible.
  std::vector<const ui::Curve*> order;
  for (const auto& c : s.result->curves)
    if (c.label.find("model") != std::string::npos) order.push_back(&c);
  for (const auto& c : s.result->curves)
    if (c.label.find("model") == std::string::npos) order.push_back(&c);
  for (const ui::Curve* cp : order) {
    const auto& c = *cp;
    if (c.label.find("FFT") != std::string::npos && !s.show_fft) continue;
    if (c.label.find("cross") != std::string::npos && !s.show_xspec) continue;
    const float width = c.label.find("updated") != std::string::npos ? 6.0f : 2.0f;
    Series m{c.label, c.f_hz, {}, colour_for(c.label), width, false};
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
    mag.markers.push_back({f, IM_COL32(255, 255, 255, 90), "resonance fr " + khz(f), true});
  for (double f : s.result->antiresonances_hz)
    mag.markers.push_back({f, IM_COL32(255, 160, 160, 90), "anti-resonance fa " + khz(f), true});
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
  if (ImGui::Checkbox("log f", &s.residual_view.log_x)) s.residual_view.fitted = false;
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("Logarithmic frequency axis for the residual plot");
  ImGui::SameLine();
  if (ImGui::Button("Fit views"))
    s.mag_view.fitted = s.phase_view.fitted = s.sv_view.fitted = s.residual_view.fitted = false;
  PlotSpec mag{"|Z|", "f [Hz]", "ohm", {}, {}, {}}, ph{"phase", "f [Hz]", "deg", {}, {}, {}};
  impedance_specs(s, mag, ph);
  PlotSpec res{"gap: residual (no diagnosis)", "f [kHz]", "dB", {}, {}, {}};
  if (s.result && s.result->diagnosis)
    res = residual_plot_spec(*s.result->diagnosis, s.residual_phase);
  PlotSpec sv{"Hankel SVs", "index", "s_k/s_1", {}, {}, {}};
  if (s.result && !s.result->singular_values.empty()) {
    sv.title = "Hankel SVs (order " + std::to_string(s.result->order) + ")";
    Series pts{"s_k/s_1", {}, s.result->singular_values, kColMeasured, 1.0f, true};
    for (std::size_t i = 0; i < pts.y.size(); ++i) pts.x.push_back(static_cast<double>(i + 1));
    sv.series.push_back(std::move(pts));
    sv.markers.push_back({s.result->order + 0.5, IM_COL32(255, 80, 80, 200)});
    sv.bands.push_back({0.5, s.result->order + 0.5, IM_COL32(255, 80, 80, 30), "",
                        "kept by Prony-SS (order " + std::to_string(s.result->order) + ")"});
  }

  // |Z| across the full width; below it the residual, the phase and the
  // singular values side by side.
  const ImVec2 avail = ImGui::GetContentRegionAvail();
  const float gap = ImGui::GetStyle().ItemSpacing.x;
  const float row2 = avail.y * 0.52f;
  plot("mag", mag, s.mag_view, ImVec2(avail.x, avail.y - row2 - ImGui::GetStyle().ItemSpacing.y));
  plot("residual", res, s.residual_view, ImVec2(avail.x * 0.42f, row2));
  ImGui::SameLine();
  plot("phase", ph, s.phase_view, ImVec2(avail.x * 0.30f - gap, row2));
  ImGui::SameLine();
  plot("sv", sv, s.sv_view, ImVec2(0, row2));
  ImGui::End();
}

}  // namespace piezo::gui
