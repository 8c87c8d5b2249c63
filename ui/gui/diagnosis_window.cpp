// Diagnosis: the gap verdict, the misfit against the noise (fit and held-out
// data), the candidate effects ranked as the diagnosis ranked them (the added
// ones first, aliases last) and the regions of the misfit. The residual plot
// itself is in the plots window (residual_plot.hpp).
#include <algorithm>

#include "ui/gui/windows.hpp"

namespace piezo::gui {

namespace {
void effects_table(const update::GapDiagnosis& d, DiagnosisShown& shown) {
  // The ranking's evidence (d chi2, held-out shrink) next to the name, the
  // value with its unit last: at the default 1280 x 800 the first three
  // columns fit, a long value scrolls in (the verdict states the named one's).
  const ImGuiTableFlags flags = ImGuiTableFlags_Borders | ImGuiTableFlags_RowBg | ImGuiTableFlags_SizingFixedFit |
                                ImGuiTableFlags_ScrollX | ImGuiTableFlags_NoHostExtendX;
  const float rows_h = ImGui::GetTextLineHeightWithSpacing() * static_cast<float>(d.effects.size() + 1) +
                       ImGui::GetStyle().ScrollbarSize + 6.0f;
  ImGui::PushStyleVar(ImGuiStyleVar_CellPadding, ImVec2(3.0f, 2.0f));
  const bool open = ImGui::BeginTable("effects", 4, flags, ImVec2(0, rows_h));
  ImGui::PopStyleVar();
  if (!open) return;
  ImGui::TableSetupScrollFreeze(1, 0);
  ImGui::TableSetupColumn("effect (ranked)");
  ImGui::TableSetupColumn("d chi2");
  ImGui::TableSetupColumn("shrink");
  ImGui::TableSetupColumn("value (sigma)");
  ImGui::TableHeadersRow();
  for (const auto& e : d.effects) {
    const bool added = std::find(d.added.begin(), d.added.end(), e.name) != d.added.end();
    ImGui::TableNextRow();
    ImGui::TableNextColumn();
    const ImVec4 colour = added     ? ImVec4(0.5f, 1, 0.5f, 1)
                          : e.alias ? ImVec4(0.65f, 0.65f, 0.65f, 1)
                                    : ImGui::GetStyleColorVec4(ImGuiCol_Text);
    ImGui::TextColored(colour, "%s", e.name.c_str());
    if (!e.note.empty() && ImGui::IsItemHovered()) ImGui::SetTooltip("%s", e.note.c_str());
    ImGui::TableNextColumn();
    if (e.fitted)
      ImGui::Text("%.1f%s", e.delta_chi2, e.significant ? " *" : "");
    else
      ImGui::TextDisabled("-");
    ImGui::TableNextColumn();
    if (e.alias) {
      ImGui::TextDisabled("alias");
      if (ImGui::IsItemHovered())
        ImGui::SetTooltip(
            "The constants mimic this effect (%.1f %% of its signature is left): a typical %.3g "
            "%s\n"
            "would read as YE11 %+.2f %%, nu12 %+.2f %%, d31 %+.2f %%, epsT33 %+.2f %%.\n"
            "Calibrate the fixture to measure it.",
            100 * e.alias_residual, e.typical, e.unit.c_str(), e.bias_y_e11_pct, e.bias_nu12_pct,
            e.bias_d31_pct, e.bias_eps_t33_pct);
    } else if (e.heldout_shrink) {
      ImGui::Text("%.0f %%", 100 * *e.heldout_shrink);
    } else {
      ImGui::TextDisabled("-");
    }
    ImGui::TableNextColumn();
    if (e.fitted)
      ImGui::Text("%.3g (%.2g) %s", e.value, e.sigma, e.unit.c_str());
    else
      ImGui::TextDisabled("-");
    ++shown.effects;
  }
  ImGui::EndTable();
  ImGui::TextDisabled("green: added to the model; grey: alias (hover); * significant");
}

void regions_table(const update::GapDiagnosis& d, DiagnosisShown& shown) {
  const ImGuiTableFlags flags =
      ImGuiTableFlags_Borders | ImGuiTableFlags_RowBg | ImGuiTableFlags_SizingFixedFit;
  if (!ImGui::BeginTable("regions", 4, flags)) return;
  ImGui::TableSetupColumn("region");
  ImGui::TableSetupColumn("kHz");
  ImGui::TableSetupColumn("chi2 share");
  ImGui::TableSetupColumn("kind");
  ImGui::TableHeadersRow();
  for (const auto& g : d.regions) {
    if (g.points == 0) continue;
    ImGui::TableNextRow();
    ImGui::TableNextColumn();
    ImGui::TextUnformatted(g.name.c_str());
    ImGui::TableNextColumn();
    ImGui::Text("%.1f-%.1f", g.f_lo_hz / 1e3, g.f_hi_hz / 1e3);
    ImGui::TableNextColumn();
    ImGui::Text("%.1f %%", 100 * g.share);
    ImGui::TableNextColumn();
    // The swatch is the region's shade in the residual plot, opaque.
    const ImU32 c = region_colour(g.kind) | IM_COL32_A_MASK;
    ImGui::ColorButton("##kind", ImGui::ColorConvertU32ToFloat4(c), ImGuiColorEditFlags_NoTooltip,
                       ImVec2(10, 10));
    ImGui::SameLine();
    // The output-error diagnosis's regions carry their phrase (the verdict's words).
    ImGui::TextUnformatted(g.description.empty() ? g.kind.c_str() : g.description.c_str());
    ++shown.regions;
  }
  ImGui::EndTable();
}
}  // namespace

void render_diagnosis_window(AppState& s) {
  ImGui::Begin("Diagnosis");
  s.diagnosis_shown = {};
  if (!s.result || !s.result->diagnosis) {
    const char* why = "No diagnosis yet: it runs after a converged update.";
    if (s.result)
      for (const auto& st : s.result->stages)
        if (st.name == "diagnose" && !st.ran) why = st.note.c_str();
    ImGui::TextWrapped("%s", why);
    ImGui::End();
    return;
  }
  const auto& d = *s.result->diagnosis;
  ImGui::PushStyleColor(ImGuiCol_Text,
                        d.gap ? ImVec4(1, 0.8f, 0.35f, 1) : ImVec4(0.5f, 1, 0.5f, 1));
  ImGui::TextWrapped("%s", d.verdict.c_str());
  ImGui::PopStyleColor();
  s.diagnosis_shown.verdict = d.verdict;
  if (d.gap_heldout)
    ImGui::Text("misfit sqrt(chi2/dof) %.2f on the fit data, %.2f held out", d.gap_fit, *d.gap_heldout);
  else
    ImGui::Text("misfit sqrt(chi2/dof) %.2f on the fit data", d.gap_fit);
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip("1 = at the noise of the repeated shots.\n%s\n%s", d.fit_description.c_str(),
                      d.heldout_description.c_str());
  if (ImGui::BeginTabBar("diag")) {
    if (ImGui::BeginTabItem("Effects")) {
      effects_table(d, s.diagnosis_shown);
      ImGui::EndTabItem();
    }
    if (ImGui::BeginTabItem("Regions")) {
      regions_table(d, s.diagnosis_shown);
      ImGui::EndTabItem();
    }
    ImGui::EndTabBar();
  }
  ImGui::End();
}

}  // namespace piezo::gui
