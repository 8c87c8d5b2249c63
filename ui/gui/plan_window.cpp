// Plan panel: R1, excitation, shots, rate, record length; transducer id,
// geometry and nominal material; the "Measure and update" button with
// progress and Cancel, and the replay of a recorded capture.
#include "jobs/nominal_material.hpp"
#include "ui/gui/windows.hpp"

namespace piezo::gui {

namespace {
const char* const kKinds[] = {"exp_decay", "sine", "chirp", "noise"};
}  // namespace

void render_plan_window(AppState& s) {
  ImGui::Begin("Plan");
  auto& p = s.request.plan;
  const bool busy = s.job.running();
  // The form scrolls in its own region; the actions (Measure and update,
  // Replay, progress and Cancel) stay below it in view at any window size
  // (issue 41 item 5: at 1280 x 800 they were scrolled out of the panel).
  const ImGuiStyle& st = ImGui::GetStyle();
  const float footer = 48 + st.ItemSpacing.y + 2 * ImGui::GetTextLineHeightWithSpacing() +
                       2 * ImGui::GetFrameHeightWithSpacing() + st.WindowPadding.y +
                       (s.error || !s.warnings.empty() ? 2 * ImGui::GetTextLineHeightWithSpacing() : 0.0f);
  ImGui::BeginChild("form", ImVec2(0, -footer), false);
  // Fields leave room for their longest label.
  ImGui::PushItemWidth(-(ImGui::CalcTextSize("Outer diameter [mm]").x + st.ItemInnerSpacing.x));
  ImGui::BeginDisabled(busy);
  ImGui::InputDouble("R1 [ohm]", &p.setup.divider_r1_ohm, 10, 100, "%.1f");
  int kind = static_cast<int>(p.excitation.kind);
  if (kind > 3) kind = 0;
  if (ImGui::Combo("Excitation", &kind, kKinds, 4))
    p.excitation.kind = static_cast<acq::Excitation>(kind);
  ImGui::InputDouble("Amplitude [V]", &p.excitation.amplitude_v, 0.1, 1, "%.3f");
  if (p.excitation.kind == acq::Excitation::ExpDecay)
    ImGui::InputDouble("Decay [1/s]", &p.excitation.decay_per_s, 100, 1000, "%.0f");
  if (p.excitation.kind == acq::Excitation::Sine)
    ImGui::InputDouble("Frequency [Hz]", &p.excitation.frequency_hz, 100, 1000, "%.1f");
  if (p.excitation.kind == acq::Excitation::Chirp) {
    ImGui::InputDouble("f start [Hz]", &p.excitation.f_start_hz, 100, 1000, "%.0f");
    ImGui::InputDouble("f stop [Hz]", &p.excitation.f_stop_hz, 100, 1000, "%.0f");
  }
  ImGui::InputInt("Shots", &p.shots);
  ImGui::InputDouble("Sample rate [S/s]", &p.sample_rate_hz, 1e5, 1e6, "%.3g");
  int n = static_cast<int>(p.samples);
  if (ImGui::InputInt("Record length", &n, 1000, 10000))
    p.samples = static_cast<std::size_t>(std::max(16, n));
  ImGui::Separator();
  ImGui::Text("Transducer and nominal model");
  ImGui::InputTextWithHint("Transducer id", "e.g. T-017", s.transducer_id, sizeof s.transducer_id);
  const auto& presets = jobs::material_presets();
  const char* current =
      presets.at(static_cast<std::size_t>(s.material_index) % presets.size()).name.c_str();
  if (ImGui::BeginCombo("Nominal material", current)) {
    for (std::size_t i = 0; i < presets.size(); ++i) {
      if (ImGui::Selectable(presets[i].name.c_str(), static_cast<int>(i) == s.material_index))
        s.material_index = static_cast<int>(i);
      if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", presets[i].description.c_str());
    }
    ImGui::EndCombo();
  }
  auto g = p.setup.geometry();
  double di = g.inner_diameter_m * 1e3, dout = g.outer_diameter_m * 1e3, len = g.length_m * 1e3;
  if (ImGui::InputDouble("Inner diameter [mm]", &di, 0.1, 1, "%.3f"))
    p.setup.inner_diameter_m = di * 1e-3;
  if (ImGui::InputDouble("Outer diameter [mm]", &dout, 0.1, 1, "%.3f"))
    p.setup.outer_diameter_m = dout * 1e-3;
  if (ImGui::InputDouble("Length [mm]", &len, 0.1, 1, "%.3f")) p.setup.length_m = len * 1e-3;
  ImGui::Checkbox("Isotropic model class (seed §6.4.3)", &s.request.isotropic);
  ImGui::InputText("Capture file", s.capture_out, sizeof s.capture_out);
  ImGui::EndDisabled();
  render_calibration_controls(s.calibration, busy);  // issue 10
  ImGui::PopItemWidth();
  ImGui::EndChild();
  ImGui::Separator();

  const bool connecting = s.instrument.state == InstrumentForm::State::Connecting;
  if (!busy) {
    ImGui::BeginDisabled(connecting);
    if (tracked_button(s, "Measure and update", ImVec2(-1, 48))) start_job(s, false);
    ImGui::TextWrapped("Or open a recorded capture and run it through the same steps:");
    ImGui::SetNextItemWidth(ImGui::GetContentRegionAvail().x - 130);
    ImGui::InputTextWithHint("##replay", "capture.h5", s.replay_path, sizeof s.replay_path);
    ImGui::SameLine();
    if (tracked_button(s, "Replay capture", ImVec2(-1, 0))) start_job(s, true);
    ImGui::SetNextItemWidth(ImGui::GetContentRegionAvail().x - 130);
    ImGui::InputTextWithHint("##heldout", "held-out capture (optional)", s.heldout_path, sizeof s.heldout_path);
    ImGui::SameLine();
    ImGui::TextDisabled("held out");
    ImGui::EndDisabled();
  } else {
    ImGui::ProgressBar(s.job.progress(), ImVec2(-1, 24), s.job.stage().c_str());
    if (tracked_button(s, "Cancel", ImVec2(-1, 0))) s.job.cancel();
    if (s.job.cancel_requested()) ImGui::TextDisabled("cancelling after the current step...");
  }
  if (s.error || !s.warnings.empty()) {
    ImGui::PushStyleColor(ImGuiCol_Text, ImVec4(1, 0.45f, 0.45f, 1));
    ImGui::TextWrapped("%s: see Results for what to do.",
                       s.error ? "The last run failed" : "The last run needs attention");
    ImGui::PopStyleColor();
  }
  ImGui::End();
}

}  // namespace piezo::gui
