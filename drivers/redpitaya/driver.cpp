#include "drivers/redpitaya/driver.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <thread>

namespace piezo::drivers::redpitaya {

namespace {
std::string num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);  // round-trips: FREQ:FIX · 16384 = the rate exactly
  return buf;
}
const std::string kWho = "redpitaya::";
}  // namespace

Session::Session(std::unique_ptr<Transport> t) : scpi_(std::move(t)) {
  idn_ = scpi_.identify();
  if (!accepts_idn(idn_))
    throw InstrumentError(scpi_.address() + ": '" + idn_ + "' is not a Red Pitaya SCPI server");
  scpi_.write("*CLS");
  scpi_.check_errors("*CLS");
}

void Session::step(const std::string& name, const std::function<void()>& f) {
  with_step_prefix("Red Pitaya, step '" + name + "': ", f);
}

void Session::configure(const std::string& name, const std::string& cmd) {
  step(name, [&] { scpi_.configure(cmd); });
}

Roles open(std::unique_ptr<Transport> t) {
  auto s = std::make_shared<Session>(std::move(t));
  return Roles{std::make_unique<Generator>(s), std::make_unique<Digitizer>(s)};
}

// ------------------------------------------------------------ generator
// Sequence after Red Pitaya's arbitrary-waveform and burst examples
// (SOUR1:FUNC ARBITRARY, SOUR1:TRAC:DATA:DATA, SOUR1:FREQ:FIX, SOUR1:VOLT,
// SOUR1:BURS:STAT BURST, SOUR1:BURS:NCYC, OUTPUT1:STATE ON, SOUR1:TRig:INT).
void Generator::load(const ArbWaveform& w) {
  const Board& b = s_->board();
  const std::string who = kWho + "Generator::load: ";
  if (w.samples.empty() || w.samples.size() > b.arb_points)
    throw std::invalid_argument(who + std::to_string(w.samples.size()) + " points (1.." +
                                std::to_string(b.arb_points) + ": the " + std::string(b.name) +
                                "'s generator buffer)");
  if (!(w.sample_rate_hz > 0 && w.sample_rate_hz <= b.dac_rate_hz))
    throw std::invalid_argument(who + "sample rate " + num(w.sample_rate_hz) + " Hz outside (0, " +
                                num(b.dac_rate_hz) + "] (the DAC clock)");
  if (!(w.peak_v > 0 && w.peak_v <= b.max_output_v))
    throw std::invalid_argument(who + "peak voltage " + num(w.peak_v) + " V outside (0, " +
                                num(b.max_output_v) +
                                "] V (the output's range, high-impedance load)");
  std::vector<float> buffer(b.arb_points, 0.0f);  // the tail is the idle level
  for (std::size_t i = 0; i < w.samples.size(); ++i) {
    if (!(std::fabs(w.samples[i]) <= 1.0))
      throw std::invalid_argument(who + "samples must lie in [-1, 1]");
    buffer[i] = static_cast<float>(w.samples[i]);
  }
  const double freq = w.sample_rate_hz / static_cast<double>(b.arb_points);
  s_->configure("output off", std::string(kOutputOff));
  s_->configure("arbitrary function", std::string(kFuncArb));
  s_->configure(
      "upload the waveform (SOUR1:TRAC:DATA:DATA, " + std::to_string(b.arb_points) + " values)",
      std::string(kArbData) + encode_arb_list(buffer));
  s_->configure("frequency (one period = the buffer)", std::string(kFrequency) + num(freq));
  s_->configure("amplitude", std::string(kAmplitude) + num(w.peak_v));
  s_->configure("offset", std::string(kOffset));
  s_->configure("burst mode", std::string(kBurstMode));
  s_->configure("one cycle per burst", std::string(kBurstOneCycle));
  s_->configure("one burst per trigger", std::string(kBurstOneRepetition));
  s_->configure("generator trigger source", std::string(kGenTriggerSource));
  loaded_ = true;
}

void Generator::output(bool on) {
  s_->configure(on ? "output on" : "output off", std::string(on ? kOutputOn : kOutputOff));
}

void Generator::trigger() {
  if (!loaded_) throw std::logic_error(kWho + "Generator::trigger: load() a waveform first");
  s_->step("trigger (SOUR1:TRig:INT)", [&] {
    s_->scpi().write(std::string(kGenTrigger));
    s_->scpi().check_errors(std::string(kGenTrigger));
  });
}

// ------------------------------------------------------------ acquisition
void Digitizer::configure(const DaqConfig& c) {
  const Board& b = s_->board();
  const std::string who = kWho + "Digitizer::configure: ";
  auto rate = choose_decimation(c.sample_rate_hz, b);
  if (!rate)
    throw std::invalid_argument(who + "sample rate " + num(c.sample_rate_hz) + " S/s outside (0, " +
                                num(b.adc_rate_hz) + "]");
  if (c.record_length < 2 || c.record_length > b.buffer_samples)
    throw std::invalid_argument(who + "record length " + std::to_string(c.record_length) +
                                " samples: the " + std::string(b.name) + " holds at most " +
                                std::to_string(b.buffer_samples) + " samples per channel");
  if (c.pretrigger_samples >= c.record_length)
    throw std::invalid_argument(who + "pretrigger must be < record length");
  const Gain* g[2];
  for (int ch = 0; ch < 2; ++ch) {
    g[ch] = gain_for_range(c.range_v[ch]);
    if (!g[ch])
      throw std::invalid_argument(who + "input " + std::to_string(ch + 1) + " range ±" +
                                  num(c.range_v[ch]) +
                                  " V: the inputs offer ±1 V (LV) or ±20 V (HV)");
  }
  if (c.coupling != Coupling::Dc1M)
    throw std::invalid_argument(who + "the inputs are DC-coupled, 1 Mohm, only");
  if (!c.external_trigger)
    throw std::invalid_argument(who +
                                "the driver triggers on the generator (ACQ:TRig AWG_PE) only");

  s_->configure("acquisition reset", std::string(kAcqReset));  // first: it resets the format too
  s_->configure("decimation " + std::to_string(rate->decimation),
                std::string(kDecimation) + std::to_string(rate->decimation));
  s_->configure("binary data", std::string(kFormatBin));
  s_->configure("data in volts", std::string(kUnitsVolts));
  for (int ch = 0; ch < 2; ++ch)
    s_->configure("input " + std::to_string(ch + 1) + " gain", gain_command(ch + 1, g[ch]->name));
  s_->configure("trigger delay", std::string(kTriggerDelay) +
                                     std::to_string(trigger_delay_for(c.pretrigger_samples, b)));
  cfg_ = c;
  rate_ = *rate;
  gain_[0] = g[0];
  gain_[1] = g[1];
  configured_ = true;
}

// ACQ:START, then the trigger source (Red Pitaya's examples set it after
// the start); the pretrigger part of the buffer fills for p / rate first.
void Digitizer::arm() {
  if (!configured_) throw std::logic_error(kWho + "Digitizer::arm: configure() first");
  s_->configure("start the acquisition", std::string(kAcqStart));
  const double fill_s = static_cast<double>(cfg_.pretrigger_samples) / rate_.sample_rate_hz;
  if (fill_s > 0) std::this_thread::sleep_for(std::chrono::duration<double>(fill_s));
  s_->configure("trigger on the generator", std::string(kTriggerOnGenerator));
}

std::vector<double> Digitizer::read_input(int input) {
  const Board& b = s_->board();
  std::vector<double> v;
  s_->step("read input " + std::to_string(input) + " (" + data_query(input) + ")", [&] {
    const auto payload = s_->scpi().query_block(data_query(input));
    auto values = decode_float_block_payload(payload);
    if (!values)
      throw InstrumentError(s_->scpi().address() + ": block of " + std::to_string(payload.size()) +
                            " bytes is not a whole number of float32 values");
    if (values->size() != b.buffer_samples)
      throw InstrumentError(s_->scpi().address() + ": " + std::to_string(values->size()) +
                            " samples, expected the whole buffer of " +
                            std::to_string(b.buffer_samples));
    // The trigger sits at sample `pretrigger` (ACQ:TRig:DLY): the record is the buffer's start.
    v.assign(values->begin(), values->begin() + static_cast<std::ptrdiff_t>(cfg_.record_length));
  });
  return v;
}

DaqRecord Digitizer::fetch(double timeout_s) {
  if (!configured_) throw std::logic_error(kWho + "Digitizer::fetch: configure() and arm() first");
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  auto poll = [&](const char* what, std::string_view query, std::string_view done) {
    s_->step(what, [&] {
      for (;;) {
        const std::string r = s_->scpi().query(std::string(query));
        if (r == done) return;
        if (std::chrono::steady_clock::now() > deadline)
          throw InstrumentError(s_->scpi().address() + ": " + std::string(query) + " still '" + r +
                                "' after " + num(timeout_s) +
                                " s (no trigger from the generator?)");
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
      }
    });
  };
  poll("wait for the trigger", kTriggerState, "TD");
  poll("wait for the buffer to fill", kBufferFilled, "1");
  DaqRecord r;
  r.v1 = read_input(1);
  r.v2 = read_input(2);
  s_->step("error queue after the reads", [&] { s_->scpi().check_errors("ACQ:SOURn:DATA?"); });
  r.sample_rate_hz = rate_.sample_rate_hz;
  r.pretrigger_samples = cfg_.pretrigger_samples;
  r.range_v[0] = gain_[0]->range_v;
  r.range_v[1] = gain_[1]->range_v;
  return r;
}

}  // namespace piezo::drivers::redpitaya
