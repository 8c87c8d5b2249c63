// Instrument panel: bench addresses (the simulated bench, tcp://, usbtmc://
// or a Comedi board), the driver families of the registry (a combo box that
// can fill in a family's twin or address), the simulated bench's effects, Connect, *IDN? of both
// instruments, the connection state and the last instrument error.
#include "ui/gui/windows.hpp"

#include <cstdio>

#include "drivers/instrument_uri.hpp"
#include "jobs/measure/sim_bench.hpp"
#include "ui/gui/driver_choices.hpp"

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
  ImGui::TextWrapped(
      "'sim' (the simulated bench; sim?awg=tektronix), tcp://HOST:PORT or "
      "usbtmc://VID:PID[/SERIAL]; "
      "DAQ also comedi:///dev/comediN?... (comedi-sim:// on the simulated bench).");
  ImGui::BeginDisabled(busy);
  // A changed address is a different bench: what was read from the old one goes.
  bool edited = ImGui::InputText("AWG", in.awg, sizeof in.awg);
  edited |= ImGui::InputText("DAQ (optional)", in.daq, sizeof in.daq);
  // The driver registry's families (`piezobench instruments`): what each is
  // and how it is chosen; "Use" fills in its in-process twin or its address.
  const auto choices = driver_choices();
  if (in.driver_choice < 0 || in.driver_choice >= static_cast<int>(choices.size()))
    in.driver_choice = 0;
  if (!choices.empty()) {
    const auto& current = choices[static_cast<std::size_t>(in.driver_choice)];
    if (ImGui::BeginCombo("Driver", current.label.c_str())) {
      for (int i = 0; i < static_cast<int>(choices.size()); ++i)
        if (ImGui::Selectable(choices[static_cast<std::size_t>(i)].label.c_str(),
                              i == in.driver_choice))
          in.driver_choice = i;
      ImGui::EndCombo();
    }
    ImGui::TextWrapped("%s", current.how.c_str());
    if (!current.twin.empty()) ImGui::TextWrapped("simulated twin: %s", current.twin.c_str());
    if (!current.awg_address.empty() || !current.daq_address.empty()) {
      ImGui::SameLine();
      if (tracked_button(s, "Use")) {
        if (!current.awg_address.empty())
          std::snprintf(in.awg, sizeof in.awg, "%s", current.awg_address.c_str());
        if (!current.daq_address.empty())
          std::snprintf(in.daq, sizeof in.daq, "%s", current.daq_address.c_str());
        edited = true;
      }
    }
  }
  if (edited) {
    in.state = InstrumentForm::State::NotConnected;
    in.idn_awg.clear();
    in.idn_daq.clear();
    in.problem.reset();
  }
  if (drivers::is_sim_address(in.awg)) {
    ImGui::InputTextWithHint("Sim effects", "e.g. series_resistance=15", in.sim_effects,
                             sizeof in.sim_effects);
    if (ImGui::IsItemHovered())
      ImGui::SetTooltip("Bench effects the simulated bench adds and the model lacks, NAME=VALUE (SI), "
                        "comma separated:\n%s",
                        jobs::sim_effect_names(4).c_str());
    ImGui::InputTextWithHint("Disturbances", "e.g. offset=0.005,hum=0.005,mains=50",
                             in.sim_disturbances, sizeof in.sim_disturbances);
    if (ImGui::IsItemHovered())
      ImGui::SetTooltip(
          "A real bench's slow disturbances on the simulated bench, comma separated (any subset):\n"
          "offset=V, hum=V, mains=50|60, pink=PCT, drift=PCT, step=PCT@SHOT, jitter=SAMPLES\n"
          "(recorded in the capture's /truth; see acquisition/README.md)");
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
