// Instrument panel: bench addresses, identity and connection state.
#include "ui/gui/windows.hpp"

namespace piezo::gui {

bool tracked_button(AppState& s, const char* label, ImVec2 size) {
  bool clicked = ImGui::Button(label, size);
  ImVec2 a = ImGui::GetItemRectMin(), b = ImGui::GetItemRectMax();
  s.button_rects[label] = ImVec4(a.x, a.y, b.x, b.y);
  return clicked;
}

void render_instrument_window(AppState& s) {
  ImGui::Begin("Instruments");
  ImGui::TextWrapped("Bench: 'sim' (embedded simulated bench), tcp://HOST:PORT or usbtmc://VID:PID[/SERIAL].");
  ImGui::InputText("AWG", s.instrument.awg, sizeof s.instrument.awg);
  ImGui::InputText("DAQ (optional)", s.instrument.daq, sizeof s.instrument.daq);
  ImGui::Text("State: %s", s.instrument.state.c_str());
  if (!s.instrument.idn_awg.empty()) ImGui::Text("AWG *IDN?: %s", s.instrument.idn_awg.c_str());
  if (!s.instrument.idn_daq.empty()) ImGui::Text("DAQ *IDN?: %s", s.instrument.idn_daq.c_str());
  if (!s.instrument.last_error.empty())
    ImGui::TextColored(ImVec4(1, 0.4f, 0.4f, 1), "Instrument error: %s", s.instrument.last_error.c_str());
  ImGui::End();
}

}  // namespace piezo::gui
