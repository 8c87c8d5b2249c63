#include "drivers/tektronix_awg/driver.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <thread>

namespace piezo::drivers::tektronix_awg {

namespace {
std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.10g", v);
  return buf;
}
std::string quoted(std::string_view s) {
  std::string q(1, '"');  // (not "\"" + s + "\"": GCC 12's -Wrestrict misfires on it)
  q.append(s);
  q.push_back('"');
  return q;
}
std::string unquoted(std::string s) {
  if (s.size() >= 2 && (s.front() == '"' || s.front() == '\'') && s.back() == s.front())
    return s.substr(1, s.size() - 2);
  return s;
}
}  // namespace

Driver::Driver(std::unique_ptr<Transport> t) : scpi_(std::move(t)) {
  idn_ = scpi_.identify();
  model_ = find_model(idn_);
  if (!model_)
    throw InstrumentError(scpi_.address() + ": '" + idn_ +
                          "' is not a supported Tektronix AWG5000/AWG7000 generator");
  scpi_.write("*CLS");
  scpi_.check_errors("*CLS");
}

void Driver::step(const std::string& name, const std::function<void()>& f) {
  with_step_prefix("Tektronix AWG, step '" + name + "': ", f);
}

void Driver::configure(const std::string& name, const std::string& cmd) {
  step(name, [&] { scpi_.configure(cmd); });
}

int Driver::run_state() {
  std::string r = scpi_.query(std::string(kRunState));
  char* end = nullptr;
  long v = std::strtol(r.c_str(), &end, 10);
  if (r.empty() || end == r.c_str() || *end != '\0' || v < 0 || v > 2)
    throw InstrumentError(scpi_.address() + ": '" + std::string(kRunState) + "' answered '" + r +
                          "', expected 0, 1 or 2");
  return static_cast<int>(v);
}

// WLISt:SIZE? and WLISt:NAME? <i> list the waveform list (predefined
// waveforms first, their names start with '*'). NEW refuses a name that
// exists and DELete one that does not, so the driver looks first.
bool Driver::waveform_exists(const std::string& name) {
  const double size = scpi_.query_double(std::string(kListSize));
  if (!(size >= 0 && size < 1e6 && size == std::floor(size)))
    throw InstrumentError(scpi_.address() + ": '" + std::string(kListSize) + "' answered " +
                          num(size));
  for (long i = 0; i < static_cast<long>(size); ++i)
    if (unquoted(scpi_.query(std::string(kListName) + std::to_string(i))) == name) return true;
  return false;
}

void Driver::load(const ArbWaveform& w) {
  const Model& m = *model_;
  const std::string who = "tektronix_awg::Driver::load: ";
  if (w.samples.size() < m.min_points || w.samples.size() > m.max_points)
    throw std::invalid_argument(who + std::to_string(w.samples.size()) + " points (" +
                                std::to_string(m.min_points) + ".." + std::to_string(m.max_points) +
                                " allowed on the " + std::string(m.idn_model) + ")");
  if (!(w.sample_rate_hz >= m.min_sample_rate_hz && w.sample_rate_hz <= m.max_sample_rate_hz))
    throw std::invalid_argument(who + "sample rate " + num(w.sample_rate_hz) + " Hz outside [" +
                                num(m.min_sample_rate_hz) + ", " + num(m.max_sample_rate_hz) +
                                "] on the " + std::string(m.idn_model));
  // The amplitude is specified into 50 ohm; the divider's input is high
  // impedance, where the generator's 50-ohm source shows twice that. So a
  // peak of peak_v at the divider is an amplitude of peak_v Vpp.
  const double amplitude = w.peak_v;
  if (!(amplitude >= m.min_amplitude_vpp && amplitude <= m.max_amplitude_vpp))
    throw std::invalid_argument(who + "peak voltage " + num(w.peak_v) + " V outside [" +
                                num(m.min_amplitude_vpp) + ", " + num(m.max_amplitude_vpp) +
                                "] V (amplitude into 50 ohm) on the " + std::string(m.idn_model));
  std::vector<float> values(w.samples.size());
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!(std::fabs(w.samples[i]) <= 1.0))
      throw std::invalid_argument(who + "samples must lie in [-1, 1]");
    values[i] = static_cast<float>(w.samples[i]);
  }
  const std::string name = quoted(kWaveformName);
  const std::string n = std::to_string(values.size());

  configure("stop", std::string(kStop));
  configure("output off", std::string(kOutputOff));
  bool exists = false;
  step("look up the waveform list", [&] { exists = waveform_exists(std::string(kWaveformName)); });
  if (exists) configure("delete the old waveform", std::string(kWaveformDelete) + name);
  configure("create the waveform", std::string(kWaveformNew) + name + "," + n + ",REAL");
  step("upload the waveform (WLISt:WAVeform:DATA)", [&] {
    const auto payload = encode_real_points(values, trigger_markers(values.size()));
    scpi_.write_block(std::string(kWaveformData) + name + ",0," + n + ",", payload);
    const std::string opc = scpi_.query("*OPC?");
    if (opc != "1" && opc != "+1")
      throw InstrumentError(scpi_.address() + ": *OPC? after the block answered '" + opc + "'");
    scpi_.check_errors("WLISt:WAVeform:DATA " + name + ",0," + n + ",<block of " +
                       std::to_string(payload.size()) + " bytes>");
  });
  configure("assign to channel 1", std::string(kAssign) + name);
  configure("sample rate", std::string(kSampleRate) + num(w.sample_rate_hz));
  if (m.select_dac_bits > 0)
    configure("DAC resolution", std::string(kDacResolution) + std::to_string(m.select_dac_bits));
  configure("run mode", std::string(kRunModeTriggered));
  configure("trigger source", std::string(kTriggerExternal));
  configure("marker 1 delay", std::string(kMarkerDelay));
  configure("marker 1 low level", std::string(kMarkerLow));
  configure("marker 1 high level", std::string(kMarkerHigh));
  configure("amplitude", std::string(kAmplitude) + num(amplitude));
  configure("offset", std::string(kOffset) + "0");
  configure("run", std::string(kRun));
  // *OPC? is said to answer 1 at once on these instruments (tm_devices'
  // notes), so the run state is polled until it waits for a trigger.
  step("wait for the run state", [&] {
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::duration<double>(run_timeout_s_);
    for (;;) {
      const int s = run_state();
      if (s == 1) return;
      if (std::chrono::steady_clock::now() > deadline)
        throw InstrumentError(scpi_.address() + ": AWGControl:RSTate? still " + std::to_string(s) +
                              " (1 = waiting for trigger) after " + num(run_timeout_s_) + " s");
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  });
}

void Driver::output(bool on) {
  configure(on ? "output on" : "output off", std::string(on ? kOutputOn : kOutputOff));
}

void Driver::trigger() {
  step("trigger (*TRG)", [&] {
    const int s = run_state();
    if (s != 1)
      throw InstrumentError(scpi_.address() + ": not waiting for a trigger (AWGControl:RSTate? = " +
                            std::to_string(s) + "); load() a waveform first");
    scpi_.write(std::string(kTrigger));
    scpi_.check_errors(std::string(kTrigger));
  });
}

}  // namespace piezo::drivers::tektronix_awg
