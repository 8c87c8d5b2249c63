// Plots: |Z| (log–log) and phase over frequency — measured vs original model vs
// updated model, with resonance / anti-resonance markers — and the Hankel
// singular values with the chosen order.
#include <cmath>
#include <complex>

#include "ui/gui/windows.hpp"

namespace piezo::gui {

namespace {
ImU32 colour_for(const std::string& label) {
  if (label.find("original") != std::string::npos) return kColOriginal;
  if (label.find("updated") != std::string::npos) return kColUpdated;
  if (label.find("FFT") != std::string::npos) return kColFft;
  if (label.find("cross") != std::string::npos) return kColXspec;
  return kColMeasured;
}
}  // namespace

void render_plots_window(AppState& s) {
  ImGui::Begin("Plots");
  ImGui::Checkbox("FFT overlay", &s.show_fft);
  ImGui::SameLine();
  ImGui::Checkbox("Cross-spectra overlay", &s.show_xspec);
  ImGui::SameLine();
  if (ImGui::Button("Fit views")) s.mag_view.fitted = s.phase_view.fitted = s.sv_view.fitted = false;
  PlotSpec mag{"|Z|", "f [Hz]", "ohm", {}, {}, {}}, ph{"phase", "f [Hz]", "deg", {}, {}, {}};
  if (s.result) {
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
      mag.series.push_back(std::move(m));
      ph.series.push_back(std::move(p));
    }
    for (double f : s.result->resonances_hz) mag.markers.push_back({f, IM_COL32(255, 255, 255, 90)});
    for (double f : s.result->antiresonances_hz) mag.markers.push_back({f, IM_COL32(255, 160, 160, 90)});
  }
  const float w = ImGui::GetContentRegionAvail().x;
  const float h = ImGui::GetContentRegionAvail().y;
  plot("mag", mag, s.mag_view, ImVec2(w, h * 0.45f));
  plot("phase", ph, s.phase_view, ImVec2(w * 0.62f, h * 0.5f));
  ImGui::SameLine();
  PlotSpec sv{"Hankel singular values", "index", "sigma/sigma1", {}, {}, {}};
  if (s.result && !s.result->singular_values.empty()) {
    Series pts{"normalised", {}, s.result->singular_values, kColMeasured, 1.0f, true};
    for (std::size_t i = 0; i < pts.y.size(); ++i) pts.x.push_back(static_cast<double>(i + 1));
    sv.series.push_back(std::move(pts));
    sv.markers.push_back({s.result->order + 0.5, IM_COL32(255, 80, 80, 200)});
  }
  plot("sv", sv, s.sv_view, ImVec2(0, h * 0.5f));
  ImGui::End();
}

}  // namespace piezo::gui
