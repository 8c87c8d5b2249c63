#include "drivers/keysight33500/driver.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "drivers/keysight33500/protocol.hpp"

namespace piezo::drivers::keysight33500 {

namespace {
std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.10g", v);
  return buf;
}
const Model* find_model(const std::string& idn) {
  const Model* found = nullptr;
  for (const auto& m : kModels)
    if (idn.find(m.idn_model) != std::string::npos) found = &m;
  return found;
}
}  // namespace

bool Driver::supports(const std::string& idn) { return find_model(idn) != nullptr; }

Driver::Driver(std::unique_ptr<Transport> t) : scpi_(std::move(t)) {
  idn_ = scpi_.identify();
  if (const Model* m = find_model(idn_)) {
    max_rate_ = m->max_sample_rate_hz;
    max_points_ = m->max_arb_points;
  }
  if (max_points_ == 0)
    throw InstrumentError(scpi_.address() + ": '" + idn_ +
                          "' is not a supported Keysight 33500B/33600A generator");
  scpi_.write("*CLS");
  scpi_.check_errors("*CLS");
}

void Driver::load(const ArbWaveform& w) {
  if (w.samples.size() < 8 || w.samples.size() > max_points_)
    throw std::invalid_argument("keysight33500::Driver::load: " + std::to_string(w.samples.size()) +
                                " points (8.." + std::to_string(max_points_) + " allowed)");
  if (!(w.sample_rate_hz > 0 && w.sample_rate_hz <= max_rate_))
    throw std::invalid_argument("keysight33500::Driver::load: sample rate " + num(w.sample_rate_hz) +
                                " Hz outside (0, " + num(max_rate_) + "]");
  if (!(w.peak_v > 0 && std::isfinite(w.peak_v)))
    throw std::invalid_argument("keysight33500::Driver::load: peak voltage must be positive");
  for (double s : w.samples)
    if (!(std::fabs(s) <= 1.0))
      throw std::invalid_argument("keysight33500::Driver::load: samples must lie in [-1, 1]");

  scpi_.configure(std::string(kOutputOff));
  scpi_.configure(std::string(kClearVolatile));
  scpi_.configure(std::string(kByteOrderSwapped));
  std::vector<std::uint8_t> payload(w.samples.size() * 4);
  for (std::size_t i = 0; i < w.samples.size(); ++i) {
    float f = static_cast<float>(w.samples[i]);
    std::memcpy(&payload[4 * i], &f, 4);  // little-endian host, FORM:BORD SWAP
  }
  scpi_.write_block(std::string(kArbDataPrefix) + std::string(kArbName) + ",", payload);
  scpi_.check_errors("SOURce1:DATA:ARBitrary");
  scpi_.configure(std::string(kSelectArb) + std::string(kArbName));
  scpi_.configure(std::string(kFunctionArb));
  scpi_.configure(std::string(kArbRate) + num(w.sample_rate_hz));
  scpi_.configure(std::string(kLoadHighZ));
  scpi_.configure(std::string(kVoltagePp) + num(2.0 * w.peak_v));
  scpi_.configure(std::string(kOffset));
  scpi_.configure(std::string(kBurstTriggered));
  scpi_.configure(std::string(kBurstOneCycle));
  scpi_.configure(std::string(kTriggerBus));
  scpi_.configure(std::string(kBurstOn));
  scpi_.configure(std::string(kSyncOn));
}

void Driver::output(bool on) { scpi_.configure(std::string(on ? kOutputOn : kOutputOff)); }

void Driver::trigger() {
  scpi_.write(std::string(kTrigger));
  scpi_.check_errors("*TRG");
}

}  // namespace piezo::drivers::keysight33500
