#include "ui/gui/calibration_prompt.hpp"

#include <string>

#include "acquisition/calibration_plan.hpp"

namespace piezo::gui {

void render_calibration_controls(CalibrationForm& f, bool busy) {
  ImGui::BeginDisabled(busy);
  ImGui::Checkbox("Fixture standards", &f.enabled);
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip("Measure the fixture (open, short, load) before the shots, as `demo` does by default");
  if (f.enabled) {  // on one line: the panel keeps its actions in view
    ImGui::SameLine();
    ImGui::Checkbox("open", &f.open);
    ImGui::SameLine();
    ImGui::Checkbox("short", &f.shrt);
    ImGui::SameLine();
    ImGui::Checkbox("load", &f.load);
    if (f.load) {
      ImGui::Indent();
      ImGui::InputDouble("Load [ohm]", &f.load_ohm, 10, 100, "%.1f");
      ImGui::InputDouble("Load C [pF]", &f.load_parallel_pf, 10, 100, "%.1f");
      if (ImGui::IsItemHovered()) ImGui::SetTooltip("Capacitance in parallel with the load standard");
      ImGui::Unindent();
    }
  }
  ImGui::EndDisabled();
}

void attach_calibration(const CalibrationForm& f, jobs::OperatorPrompt& prompt,
                        jobs::PipelineRequest& req) {
  req.calibration.clear();
  if (!f.enabled) return;
  std::string list;
  for (auto [on, name] :
       {std::pair{f.open, "open"}, std::pair{f.shrt, "short"}, std::pair{f.load, "load"}})
    if (on) {
      if (!list.empty()) list += ',';
      list += name;
    }
  if (list.empty()) return;
  req.calibration = acq::parse_calibration_list(
      list, f.load_ohm,
      f.load_parallel_pf > 0 ? std::optional<double>(f.load_parallel_pf * 1e-12) : std::nullopt);
  req.prompt = [&prompt](const std::string& text) { return prompt.ask(text); };
}

void render_calibration_prompt(jobs::OperatorPrompt& prompt) {
  const auto q = prompt.question();
  constexpr const char* kTitle = "Connect the calibration standard";
  if (q && !ImGui::IsPopupOpen(kTitle)) ImGui::OpenPopup(kTitle);
  if (ImGui::BeginPopupModal(kTitle, nullptr, ImGuiWindowFlags_AlwaysAutoResize)) {
    if (!q) {  // answered or cancelled elsewhere
      ImGui::CloseCurrentPopup();
    } else {
      ImGui::PushTextWrapPos(ImGui::GetFontSize() * 32.0f);
      ImGui::TextUnformatted(q->c_str());
      ImGui::PopTextWrapPos();
      ImGui::Separator();
      if (ImGui::Button("Connected - continue", ImVec2(220, 0))) {
        prompt.answer(true);
        ImGui::CloseCurrentPopup();
      }
      ImGui::SameLine();
      if (ImGui::Button("Cancel the run", ImVec2(160, 0))) {
        prompt.answer(false);
        ImGui::CloseCurrentPopup();
      }
    }
    ImGui::EndPopup();
  }
}

}  // namespace piezo::gui
