// Results: the error that stopped the last run (with what to do), the limits
// file and pass/fail against it with the reasons, original
// vs updated parameters with the change in %, the stages that ran, the exports (CSV, Touchstone,
// JSON report, PNG of the window) and the log. The gap verdict and effect ranking are in the
// diagnosis window.
#include "ui/gui/windows.hpp"

#include <cmath>

#include "jobs/text/uncertain_text.hpp"

namespace piezo::gui {

namespace {
// A table cell's value ± σ in the GUI's Latin-1 font ("-" for a σ that is not finite).
const dsp::UncertainStyle kGuiCell{true, 6, "sigma not identifiable", "-"};
}  // namespace


namespace {
void parameter_table(const jobs::PipelineResult& r) {
  const bool sim = std::any_of(r.params.begin(), r.params.end(),
                               [](const auto& p) { return p.truth.has_value(); });
  const bool seed = std::any_of(r.params.begin(), r.params.end(), [](const auto& p) { return p.cmcm.has_value(); });
  // Which method `updated` holds, and the fit's summary: a tooltip on the
  // values (the table keeps its height, the exports stay in view).
  const char* method = r.update_method == "output-error" ? "output-error fit of the samples (with sigma)"
                       : r.update_method == "cmcm"       ? "the seed's extended CMCM (sigma from its features)"
                                                         : "least squares on the seed's features (sigma from them)";
  const bool corr = r.corrected.has_value();
  if (corr) {  // the result is the model refitted with the effect the diagnosis named
    ImGui::PushStyleColor(ImGuiCol_Text, ImVec4(0.4f, 0.8f, 1.0f, 1.0f));
    ImGui::TextWrapped("Result %s; \"without effect\": the update's constants before the diagnosis",
                       r.corrected->label.c_str());
    ImGui::PopStyleColor();
  }
  // Columns sized to their content (value and sigma in one cell, σ to two
  // significant digits; the relative σ in the value's tooltip), a horizontal
  // scroll bar where the panel is narrower. At the default 1280 × 800 the
  // parameter, its value, status and change fit; original, the uncorrected
  // value, CMCM and the truth scroll in.
  const int cols = 5 + (seed ? 1 : 0) + (sim ? 1 : 0) + (corr ? 1 : 0);
  const float rows_h = ImGui::GetTextLineHeightWithSpacing() * static_cast<float>(r.params.size() + 1) +
                       ImGui::GetStyle().ScrollbarSize + 6.0f;
  ImGui::PushStyleVar(ImGuiStyleVar_CellPadding, ImVec2(3.0f, 2.0f));  // (4, 2) by default: 10 px more for text
  const bool open = ImGui::BeginTable("params", cols,
                                      ImGuiTableFlags_Borders | ImGuiTableFlags_RowBg | ImGuiTableFlags_SizingFixedFit |
                                          ImGuiTableFlags_ScrollX | ImGuiTableFlags_NoHostExtendX,
                                      ImVec2(0, rows_h));
  ImGui::PopStyleVar();
  if (!open) return;
  ImGui::TableSetupScrollFreeze(1, 0);
  ImGui::TableSetupColumn("parameter");  // its unit in the cell: the header is the column's widest text
  ImGui::TableSetupColumn("updated ± sigma");
  ImGui::TableSetupColumn("status");
  ImGui::TableSetupColumn("change %");
  ImGui::TableSetupColumn("original");
  if (corr) ImGui::TableSetupColumn("without effect");
  if (seed) ImGui::TableSetupColumn("CMCM (seed)");
  if (sim) ImGui::TableSetupColumn("true (sim)");
  ImGui::TableHeadersRow();
  for (const auto& p : r.params) {
    ImGui::TableNextRow();
    ImGui::TableNextColumn();
    ImGui::Text("%s [%s]", p.name.c_str(), p.unit.c_str());
    ImGui::TableNextColumn();
    const double rel = p.sigma ? 100.0 * *p.sigma / std::abs(p.updated) : NAN;
    ImGui::TextUnformatted(jobs::format_uncertain(p.updated, p.sigma.value_or(NAN), {}, kGuiCell).c_str());
    if (ImGui::IsItemHovered()) {  // the relative sigma here keeps the first four columns in a 1280-wide window
      const std::string rel_text = std::isfinite(rel) ? "relative sigma " + jobs::format_value(rel, "%", 2) + "\n" : "";
      if (r.output_error && r.output_error->ok())
        ImGui::SetTooltip("%s%s\ncorr(nu12, d31) %+.2f, chi2/dof %.3g (limit %.3g), %s", rel_text.c_str(), method,
                          r.output_error->corr_nu12_d31, r.output_error->chi2_per_dof,
                          r.output_error->chi2_limit,
                          update::damping_summary(*r.output_error).c_str());
      else
        ImGui::SetTooltip("%s%s", rel_text.c_str(), method);
    }
    ImGui::TableNextColumn();
    if (p.status == "ok") {
      ImGui::TextUnformatted("ok");
    } else {
      ImGui::TextColored(ImVec4(1.0f, 0.6f, 0.2f, 1.0f), "%s", p.status.c_str());
      if (ImGui::IsItemHovered() && r.output_error && !corr)  // why, and what would pin it
        for (const auto& q : r.output_error->parameters)
          if (q.name == p.name && !q.note.empty()) ImGui::SetTooltip("%s", q.note.c_str());
    }
    ImGui::TableNextColumn();
    ImGui::Text("%+.2f", p.original != 0 ? 100.0 * (p.updated - p.original) / p.original : 0.0);
    ImGui::TableNextColumn();
    ImGui::Text("%.5g", p.original);
    if (corr) {
      ImGui::TableNextColumn();
      if (p.uncorrected)
        ImGui::Text("%s (%s)",
                    jobs::format_uncertain(*p.uncorrected, p.uncorrected_sigma.value_or(NAN), {}, kGuiCell).c_str(),
                    p.uncorrected_status.c_str());
      else
        ImGui::TextDisabled("-");
    }
    if (seed) {
      ImGui::TableNextColumn();
      if (p.cmcm)
        ImGui::Text("%.5g", *p.cmcm);
      else
        ImGui::TextDisabled("-");
    }
    if (!sim) continue;
    ImGui::TableNextColumn();
    if (p.truth)
      ImGui::Text("%.5g", *p.truth);
    else
      ImGui::TextDisabled("-");
  }
  ImGui::EndTable();
}
// The bench's slow disturbances the output-error fit modelled, and the shots'
// agreement (issue 33): numbers the fit already holds, drawn only.
void disturbances_block(const update::OeResult& o) {
  const auto& b = o.baseline;
  const auto& c = o.shot_consistency;
  if (!b.any() && !b.channel_offsets && !c.tested) return;
  if (!ImGui::CollapsingHeader("Bench disturbances")) return;
  if (b.channel_offsets)
    ImGui::Text("offsets (pretrigger): ch1 %+.3g mV +/- %.2g, ch2 %+.3g mV +/- %.2g", 1e3 * b.channel_offset_v[0],
                1e3 * b.channel_offset_sigma_v[0], 1e3 * b.channel_offset_v[1], 1e3 * b.channel_offset_sigma_v[1]);
  if (b.modelled) {
    ImGui::Text("baseline ch1-ch2 projected out: slope %.3g +/- %.2g V/s (chi2 %.0f for %d parameters)",
                b.slope_v_per_s, b.slope_sigma_v_per_s, b.delta_chi2, b.dof);
    if (b.harmonics > 0 && std::isfinite(b.hum_v))
      ImGui::Text("mains hum %.0f Hz%s: %.3g mV +/- %.2g", b.mains_hz, b.mains_distinguishable ? "" : " (or 60/50)",
                  1e3 * b.hum_v, 1e3 * b.hum_sigma_v);
    else
      ImGui::TextDisabled("mains hum: inside the polynomial (record below half a mains cycle)");
  } else {
    ImGui::TextDisabled("no baseline wander beyond the offsets");
  }
  if (b.pink)
    ImGui::Text("1/f noise: %.3g mV rms in the band, weighted as noise", 1e3 * b.pink_rms_v);
  if (c.tested) {
    if (c.consistent)
      ImGui::Text("%d shots consistent (chi2 %.0f for %d dof)", c.shots, c.chi2, c.dof);
    else
      ImGui::TextColored(ImVec4(1, 0.6f, 0.2f, 1), "%s", c.summary.c_str());
    if (c.aligned) ImGui::TextDisabled("shots aligned for trigger jitter before averaging");
  }
}

// Pass / fail against the loaded limits, with one line per reason.
void limits_line(const jobs::report::CaptureVerdict& v, const std::string& file) {
  const bool pass = v.status == "pass";
  // A banner a technician reads across the bench: white on green or red, twice the text size.
  ImGui::PushStyleColor(ImGuiCol_Button, pass ? ImVec4(0.15f, 0.55f, 0.2f, 1) : ImVec4(0.75f, 0.15f, 0.15f, 1));
  ImGui::PushStyleColor(ImGuiCol_ButtonHovered, pass ? ImVec4(0.15f, 0.55f, 0.2f, 1) : ImVec4(0.75f, 0.15f, 0.15f, 1));
  ImGui::PushStyleColor(ImGuiCol_ButtonActive, pass ? ImVec4(0.15f, 0.55f, 0.2f, 1) : ImVec4(0.75f, 0.15f, 0.15f, 1));
  ImGui::SetWindowFontScale(2.0f);
  ImGui::Button(pass ? "  PASS  " : "  FAIL  ");
  ImGui::SetWindowFontScale(1.0f);
  ImGui::PopStyleColor(3);
  ImGui::SameLine();
  ImGui::TextDisabled("limits: %s", file.c_str());
  for (const auto& reason : v.reasons) ImGui::TextColored(ImVec4(1.0f, 0.6f, 0.5f, 1), "  %s", reason.c_str());
}
}  // namespace

void render_results_window(AppState& s) {
  ImGui::Begin("Results");
  // What stopped the last run, or needs the technician's action, comes first.
  if (s.error) show_problem(*s.error);
  for (const auto& w : s.warnings) show_problem(w);
  // Acceptance limits (as `replay --limits`): each result is judged against them.
  ImGui::SetNextItemWidth(ImGui::GetContentRegionAvail().x - 90);
  ImGui::InputTextWithHint("##limits", "limits.toml (optional: pass/fail of each result)", s.limits_path,
                           sizeof s.limits_path);
  ImGui::SameLine();
  if (tracked_button(s, "Limits...", ImVec2(-1, 0))) load_limits(s);
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip("Load acceptance limits (README, 'Limits and the lot report'): the result is shown "
                      "as pass or fail with the reasons");
  if (!s.result && !s.error) {
    ImGui::TextWrapped(
        "No result yet. Set the plan and press 'Measure and update', or replay a capture.");
  } else if (s.result) {
    const auto& r = *s.result;
    ImGui::TextWrapped("Capture: %s (%d shots)", r.capture_path.c_str(), r.shots);
    if (s.verdict)
      limits_line(*s.verdict, s.limits ? s.limits->source : std::string());
    else
      ImGui::TextColored(ImVec4(1.0f, 0.8f, 0.3f, 1), "No limits loaded: no pass/fail (Limits...)");
    if (r.params.empty())
      ImGui::TextDisabled("No updated parameters (see the stages below).");
    else
      parameter_table(r);
    if (r.output_error) disturbances_block(*r.output_error);
    if (!r.curves.empty()) {  // the exports need at least the impedance estimate
      ImGui::SetNextItemWidth(150);
      ImGui::InputText("##export", s.export_base, sizeof s.export_base);
      if (ImGui::IsItemHovered()) ImGui::SetTooltip("File name without extension for the exports");
      ImGui::SameLine();
      if (tracked_button(s, "CSV")) export_result(s, ExportFormat::Csv);
      ImGui::SameLine();
      if (tracked_button(s, "Touchstone")) export_result(s, ExportFormat::Touchstone);
      ImGui::SameLine();
      if (tracked_button(s, "JSON")) export_result(s, ExportFormat::Json);
      ImGui::SameLine();
      if (tracked_button(s, "PNG")) s.png_request = std::string(s.export_base) + ".png";
    }
    for (const auto& st : r.stages)
      ImGui::TextColored(st.ran ? ImVec4(0.5f, 1, 0.5f, 1) : ImVec4(0.7f, 0.7f, 0.7f, 1),
                         "%s %s: %s", st.ran ? "[ran]" : "[skipped]", st.name.c_str(),
                         st.note.c_str());
    for (const auto& w : r.warnings)
      ImGui::TextColored(ImVec4(1, 0.8f, 0.3f, 1), "warning: %s", w.c_str());
  }
  ImGui::BeginChild("log", ImVec2(0, 0), true, ImGuiWindowFlags_HorizontalScrollbar);
  for (const auto& l : s.log) ImGui::TextUnformatted(l.c_str());
  if (ImGui::GetScrollY() >= ImGui::GetScrollMaxY())
    ImGui::SetScrollHereY(1.0f);  // follow the tail
  ImGui::EndChild();
  ImGui::End();
}

}  // namespace piezo::gui
