// Small widgets shared by the windows.
#include <cctype>
#include <string>

#include "ui/gui/windows.hpp"

namespace piezo::gui {

bool tracked_button(AppState& s, const char* label, ImVec2 size) {
  bool clicked = ImGui::Button(label, size);
  ImVec2 a = ImGui::GetItemRectMin(), b = ImGui::GetItemRectMax();
  s.button_rects[label] = ImVec4(a.x, a.y, b.x, b.y);
  return clicked;
}

bool tracked_checkbox(AppState& s, const char* label, bool* value) {
  const bool changed = ImGui::Checkbox(label, value);
  ImVec2 a = ImGui::GetItemRectMin(), b = ImGui::GetItemRectMax();
  s.button_rects[label] = ImVec4(a.x, a.y, b.x, b.y);
  return changed;
}

void show_problem(const Problem& p) {
  const bool error = p.kind != ErrorKind::Attention;
  ImGui::PushStyleColor(ImGuiCol_Text,
                        error ? ImVec4(1, 0.45f, 0.45f, 1) : ImVec4(1, 0.75f, 0.3f, 1));
  std::string heading = kind_name(p.kind);
  heading[0] = static_cast<char>(std::toupper(static_cast<unsigned char>(heading[0])));
  ImGui::TextWrapped("%s (%s): %s", heading.c_str(), p.stage.c_str(), p.message.c_str());
  ImGui::PopStyleColor();
  ImGui::PushStyleColor(ImGuiCol_Text, ImVec4(1, 0.85f, 0.55f, 1));
  ImGui::TextWrapped("What to do: %s", p.advice.c_str());
  ImGui::PopStyleColor();
}

}  // namespace piezo::gui
