#include "drivers/infiniium/driver.hpp"

#include <chrono>
#include <cmath>
#include <cstring>
#include <thread>

#include "drivers/infiniium/protocol.hpp"

namespace piezo::drivers::infiniium {

namespace {
std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.10g", v);
  return buf;
}
const char* input_of(Coupling c) {
  switch (c) {
    case Coupling::Dc50: return "DC50";
    case Coupling::Ac: return "AC";
    default: return "DC";
  }
}
// *IDN?: "KEYSIGHT TECHNOLOGIES,DSO9104A,serial,firmware"; the last row whose prefix fits.
const Model* find_model(const std::string& idn) {
  auto c1 = idn.find(',');
  std::string model = c1 == std::string::npos ? "" : idn.substr(c1 + 1, idn.find(',', c1 + 1) - c1 - 1);
  const Model* found = nullptr;
  for (const auto& m : kModels)
    if (model.starts_with(m.idn_prefix)) found = &m;
  return found;
}
}  // namespace

bool Driver::supports(const std::string& idn) { return find_model(idn) != nullptr; }

Driver::Driver(std::unique_ptr<Transport> t) : scpi_(std::move(t)) {
  idn_ = scpi_.identify();
  if (const Model* m = find_model(idn_)) {
    max_rate_ = m->max_sample_rate_hz;
    max_points_ = m->max_points;
  }
  if (max_points_ == 0)
    throw InstrumentError(scpi_.address() + ": '" + idn_ + "' is not a supported Infiniium oscilloscope");
  scpi_.write("*CLS");
  scpi_.configure(std::string(kHeaderOff));
}

void Driver::configure(const DaqConfig& c) {
  if (!(c.sample_rate_hz > 0 && c.sample_rate_hz <= max_rate_))
    throw std::invalid_argument("infiniium::Driver::configure: sample rate " + num(c.sample_rate_hz) +
                                " Hz outside (0, " + num(max_rate_) + "]");
  if (c.record_length < 16 || c.record_length > max_points_)
    throw std::invalid_argument("infiniium::Driver::configure: record length " +
                                std::to_string(c.record_length) + " outside [16, " +
                                std::to_string(max_points_) + "]");
  if (c.pretrigger_samples >= c.record_length)
    throw std::invalid_argument("infiniium::Driver::configure: pretrigger must be < record length");
  for (double r : c.range_v)
    if (!(r > 0 && std::isfinite(r)))
      throw std::invalid_argument("infiniium::Driver::configure: channel range must be positive");

  scpi_.configure(std::string(kRealTime));
  for (int ch = 1; ch <= 2; ++ch) {
    std::string p = ":CHANnel" + std::to_string(ch);
    scpi_.configure(p + ":DISPlay ON");
    scpi_.configure(p + ":INPut " + input_of(c.coupling));
    scpi_.configure(p + ":RANGe " + num(2.0 * c.range_v[ch - 1]));  // full scale = 2 × ±range
    scpi_.configure(p + ":OFFSet 0");
  }
  scpi_.configure(std::string(kSampleRate) + num(c.sample_rate_hz));
  scpi_.configure(std::string(kPoints) + std::to_string(c.record_length));
  scpi_.configure(std::string(kRefLeft));
  scpi_.configure(std::string(kPosition) + num(-static_cast<double>(c.pretrigger_samples) / c.sample_rate_hz));
  scpi_.configure(std::string(kEdgeMode));
  scpi_.configure(std::string(c.external_trigger ? kTrigAux : kTrigChan1));
  scpi_.configure(std::string(kSlopePos));
  scpi_.configure(std::string(kWordFormat));
  scpi_.configure(std::string(kLsbFirst));
  scpi_.configure(std::string(kStreamingOff));
  // The instrument may coerce rate and depth: refuse rather than mislabel the data.
  double rate = scpi_.query_double(":ACQuire:SRATe:ANALog?");
  if (std::fabs(rate - c.sample_rate_hz) > 1e-9 * c.sample_rate_hz)
    throw InstrumentError(scpi_.address() + ": sample rate coerced to " + num(rate) + " Hz (asked " +
                          num(c.sample_rate_hz) + ")");
  cfg_ = c;
  configured_ = true;
}

void Driver::arm() {
  if (!configured_) throw std::logic_error("infiniium::Driver::arm: configure() first");
  scpi_.query(std::string(kAcqDone));  // reading :ADER? clears the event
  scpi_.write(std::string(kSingle));
  scpi_.check_errors(":SINGle");
}

std::vector<double> Driver::read_channel(int ch) {
  scpi_.configure(":WAVeform:SOURce CHANnel" + std::to_string(ch));
  double yinc = scpi_.query_double(":WAVeform:YINCrement?");
  double yorg = scpi_.query_double(":WAVeform:YORigin?");
  auto bytes = scpi_.query_block(":WAVeform:DATA?");
  if (bytes.size() != 2 * cfg_.record_length)
    throw InstrumentError(scpi_.address() + ": channel " + std::to_string(ch) + " returned " +
                          std::to_string(bytes.size() / 2) + " points, expected " +
                          std::to_string(cfg_.record_length));
  std::vector<double> v(cfg_.record_length);
  for (std::size_t i = 0; i < v.size(); ++i) {
    std::int16_t code;
    std::memcpy(&code, &bytes[2 * i], 2);  // LSBFirst on a little-endian host
    v[i] = yorg + yinc * code;
  }
  return v;
}

DaqRecord Driver::fetch(double timeout_s) {
  auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  for (;;) {
    std::string done = scpi_.query(std::string(kAcqDone));
    if (done == "1" || done == "+1") break;
    if (std::chrono::steady_clock::now() > deadline)
      throw InstrumentError(scpi_.address() + ": no trigger / acquisition not done after " +
                            num(timeout_s) + " s");
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  DaqRecord r;
  r.v1 = read_channel(1);
  r.v2 = read_channel(2);
  r.sample_rate_hz = cfg_.sample_rate_hz;
  r.pretrigger_samples = cfg_.pretrigger_samples;
  r.range_v[0] = cfg_.range_v[0];
  r.range_v[1] = cfg_.range_v[1];
  return r;
}

}  // namespace piezo::drivers::infiniium
