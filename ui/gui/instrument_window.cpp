// Instrument panel: bench addresses (the simulated bench, tcp:// or
// usbtmc://), the simulated bench's effects, Connect, *IDN? of both
// instruments, the connection state and the last instrument error.
#include "ui/gui/windows.hpp"

namespace piezo::gui {

namespace {
const char* state_text(InstrumentForm::State st) {
  switch (st) {
    case InstrumentForm::State::NotConnected:
      return "not connected";
    case InstrumentForm::State::Connecting:
      return "connecting...";
    case InstrumentForm::State::Connected:
      return "connected";
    case InstrumentForm::State::Replay:
      return "replay (no instrument used)";
    case InstrumentForm::State::Measuring:
      return "in use by the measurement";
    case InstrumentForm::State::Error:
      break;
  }
  return "error";
}

ImVec4 state_colour(InstrumentForm::State st) {
  switch (st) {
    case InstrumentForm::State::Connected:
      return ImVec4(0.5f, 1, 0.5f, 1);
    case InstrumentForm::State::Error:
      return ImVec4(1, 0.45f, 0.45f, 1);
    case InstrumentForm::State::Connecting:
    case InstrumentForm::State::Measuring:
      return ImVec4(1, 0.85f, 0.4f, 1);
    default:
      return ImVec4(0.75f, 0.75f, 0.75f, 1);
  }
}
}  // namespace

void render_instrument_window(AppState& s) {
  ImGui::Begin("Instruments");
  auto& in = s.instrument;
  const bool busy = s.job.running() || in.state == InstrumentForm::State::Connecting;
  ImGui::TextWrapped("'sim' (the simulated bench), tcp://HOST:PORT or usbtmc://VID:PID[/SERIAL].");
  ImGui::BeginDisabled(busy);
  // A changed address is a different bench: what was read from the old one goes.
  bool edited = ImGui::InputText("AWG", in.awg, sizeof in.awg);
  edited |= ImGui::InputText("DAQ (optional)", in.daq, sizeof in.daq);
  if (edited) {
    in.state = InstrumentForm::State::NotConnected;
    in.idn_awg.clear();
    in.idn_daq.clear();
    in.problem.reset();
  }
  if (std::string(in.awg) == "sim") {
    ImGui::InputTextWithHint("Sim effects", "e.g. series_resistance=15", in.sim_effects,
                             sizeof in.sim_effects);
    if (ImGui::IsItemHovered())
      ImGui::SetTooltip(
          "Bench effects the simulated bench adds and the model lacks, NAME=VALUE (SI), "
          "comma separated:\nseries_resistance, parallel_capacitance, daq_input_resistance, "
          "dielectric_loss,\nchannel_skew, channel_gain, r1_tolerance, mechanical_damping, "
          "mass_loading");
  }
  if (tracked_button(s, "Connect")) connect_instruments(s);
  ImGui::EndDisabled();
  ImGui::SameLine();
  ImGui::TextColored(state_colour(in.state), "%s", state_text(in.state));
  if (in.state == InstrumentForm::State::Connected || !in.idn_awg.empty()) {
    ImGui::TextWrapped("AWG *IDN?: %s", in.idn_awg.c_str());
    ImGui::TextWrapped("DAQ *IDN?: %s", in.idn_daq.c_str());
  }
  if (in.problem) show_problem(*in.problem);
  ImGui::End();
}

}  // namespace piezo::gui
