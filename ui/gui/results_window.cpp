// Results: original vs updated parameters with the change in %, the stages
// that ran, the gap verdict, warnings and the log.
#include "ui/gui/windows.hpp"
#include "ui/report_export.hpp"

namespace piezo::gui {

void render_results_window(AppState& s) {
  ImGui::Begin("Results");
  if (!s.result) {
    ImGui::TextWrapped("No result yet. Set the plan and press 'Measure and update'.");
  } else {
    const auto& r = *s.result;
    ImGui::Text("Capture: %s (%d shots)", r.capture_path.c_str(), r.shots);
    if (ImGui::BeginTable("params", 5, ImGuiTableFlags_Borders | ImGuiTableFlags_RowBg)) {
      ImGui::TableSetupColumn("parameter");
      ImGui::TableSetupColumn("original");
      ImGui::TableSetupColumn("updated");
      ImGui::TableSetupColumn("change %");
      ImGui::TableSetupColumn("true (sim)");
      ImGui::TableHeadersRow();
      for (const auto& p : r.params) {
        ImGui::TableNextRow();
        ImGui::TableNextColumn();
        ImGui::Text("%s [%s]", p.name.c_str(), p.unit.c_str());
        ImGui::TableNextColumn();
        ImGui::Text("%.5g", p.original);
        ImGui::TableNextColumn();
        ImGui::Text("%.5g", p.updated);
        ImGui::TableNextColumn();
        ImGui::Text("%+.2f", p.original != 0 ? 100.0 * (p.updated - p.original) / p.original : 0.0);
        ImGui::TableNextColumn();
        if (p.truth) ImGui::Text("%.5g", *p.truth);
        else ImGui::TextDisabled("-");
      }
      ImGui::EndTable();
    }
    if (!r.verdict.empty()) ImGui::TextWrapped("Gap verdict: %s", r.verdict.c_str());
    ImGui::Separator();
    for (const auto& st : r.stages)
      ImGui::TextColored(st.ran ? ImVec4(0.5f, 1, 0.5f, 1) : ImVec4(0.7f, 0.7f, 0.7f, 1), "%s %s: %s",
                         st.ran ? "[ran]" : "[skipped]", st.name.c_str(), st.note.c_str());
    for (const auto& w : r.warnings) ImGui::TextColored(ImVec4(1, 0.8f, 0.3f, 1), "warning: %s", w.c_str());
    ImGui::Separator();
    ImGui::SetNextItemWidth(260);
    ImGui::InputText("##export", s.export_base, sizeof s.export_base);
    const std::string base = s.export_base;
    auto do_export = [&](const char* label, const std::string& path, auto fn) {
      ImGui::SameLine();
      if (ImGui::Button(label)) {
        try {
          fn(r, path);
          s.log.push_back("exported " + path);
        } catch (const std::exception& e) {
          s.error = std::string(e.what()) + " (check the folder exists and is writable)";
        }
      }
    };
    do_export("CSV", base + ".csv", ui::export_csv);
    do_export("Touchstone", base + ".s1p", ui::export_touchstone);
    do_export("JSON", base + ".json", ui::export_json);
    ImGui::SameLine();
    if (ImGui::Button("PNG")) s.png_request = base + ".png";
  }
  ImGui::Separator();
  ImGui::BeginChild("log", ImVec2(0, 0), true);
  for (const auto& l : s.log) ImGui::TextUnformatted(l.c_str());
  ImGui::EndChild();
  ImGui::End();
}

}  // namespace piezo::gui
