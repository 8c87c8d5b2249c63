#include "drivers/sim/sim_redpitaya.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

#include "drivers/ieee488_block.hpp"
#include "drivers/redpitaya/protocol.hpp"
#include "drivers/sim/scpi_args.hpp"

namespace piezo::drivers::sim {

namespace rp = piezo::drivers::redpitaya;

namespace {
std::string first(const std::vector<std::string>& p) { return p.empty() ? "" : upper(p[0]); }
}  // namespace

SimRedPitaya::SimRedPitaya(std::shared_ptr<SimBench> bench) : bench_(std::move(bench)) {
  if (!bench_) throw std::invalid_argument("SimRedPitaya: null bench");
  if (bench_->imperfections().adc_bits != rp::kStemlab125_14.adc_bits)
    throw std::invalid_argument(
        "SimRedPitaya: the STEMlab 125-14 digitises with 14 bits, the bench with " +
        std::to_string(bench_->imperfections().adc_bits));
  std::lock_guard lock(bench_->mutex());
  apply_acquisition_settings();
}

// The acquisition's settings as the shared DaqState: the whole buffer, the
// trigger at sample 8192 - delay, full scale 2 × the gain's range.
void SimRedPitaya::apply_acquisition_settings() {
  const auto& b = rp::kStemlab125_14;
  DaqState& d = bench_->daq();
  d.sample_rate_hz = b.adc_rate_hz / acq_.decimation;
  d.points = b.buffer_samples;
  const long trigger_at = static_cast<long>(b.buffer_samples / 2) - acq_.delay;
  d.position_s = -static_cast<double>(trigger_at) / d.sample_rate_hz;
  for (int ch = 0; ch < 2; ++ch)
    d.full_scale_v[ch] = 2.0 * rp::kGains[acq_.high_gain[ch] ? 1 : 0].range_v;
  d.aux_trigger = true;
  d.armed = acq_.armed;
}

void SimRedPitaya::fire() {
  if (!gen_.arb_function || gen_.arb.empty()) {
    push_error(-221, "Settings conflict; no arbitrary waveform loaded");
    return;
  }
  if (!gen_.burst || gen_.cycles != 1 || gen_.repetitions != 1) {
    push_error(-221, "Settings conflict; the simulator plays single one-cycle bursts only");
    return;
  }
  AwgState& a = bench_->awg();
  a.arb = gen_.arb;
  a.arb_rate_hz = static_cast<double>(gen_.arb.size()) * gen_.freq_hz;
  a.vpp = 2.0 * gen_.amplitude_v;
  a.offset_v = gen_.offset_v;
  a.output_on = gen_.output_on;
  apply_acquisition_settings();
  bench_->fire();  // records only if armed (ACQ:TRig AWG_PE) and the output is on
  if (bench_->daq().done) acq_.armed = false;
}

void SimRedPitaya::data_reply(int input, Reply& out) {
  DaqState& d = bench_->daq();
  const auto& codes = d.codes[input - 1];
  if (codes.empty() || d.armed) {
    push_error(-230, "Data corrupt or stale; no acquisition");
    append(out, acq_.binary ? "#10\r\n" : "{}\r\n");
    return;
  }
  std::vector<float> v(codes.size());
  for (std::size_t i = 0; i < v.size(); ++i)
    v[i] = static_cast<float>(d.yincrement[input - 1] * codes[i]);
  if (!acq_.binary) {
    std::string s = "{";
    char buf[32];
    for (std::size_t i = 0; i < v.size(); ++i) {
      std::snprintf(buf, sizeof buf, "%s%f", i ? "," : "", static_cast<double>(v[i]));
      s += buf;
    }
    append(out, s + "}\r\n");
    return;
  }
  const auto payload = rp::encode_float_block_payload(v);
  append(out, block_header(payload.size()));
  out.bytes.insert(out.bytes.end(), payload.begin(), payload.end());
  append(out, "\r\n");
}

bool SimRedPitaya::generator(const scpi::Command& c, Reply& out) {
  using scpi::match;
  std::vector<int> sfx;
  double v = 0;
  auto channel_ok = [&] {
    if (!sfx.empty() && sfx[0] == 1) return true;
    push_error(-114, "Header suffix out of range; the simulator wires output 1 only");
    return false;
  };
  if (match("GENerator:RST", c.header)) {
    gen_ = Gen{};
  } else if (match("OUTPUT#:STATe", c.header, &sfx)) {
    if (!channel_ok()) return true;
    if (c.query)
      append(out, gen_.output_on ? "ON\r\n" : "OFF\r\n");
    else
      gen_.output_on = first(c.params) == "ON" || first(c.params) == "1";
  } else if (match("SOURce#:FUNCtion", c.header, &sfx) && !c.query) {
    if (!channel_ok()) return true;
    gen_.arb_function = first(c.params) == "ARBITRARY";
    if (!gen_.arb_function)
      push_error(-224, "Illegal parameter value; the simulator offers ARBITRARY only");
  } else if (match("SOURce#:TRACe:DATA:DATA", c.header, &sfx) && !c.query) {
    if (!channel_ok()) return true;
    auto values = rp::decode_arb_list(c.params, rp::kStemlab125_14.arb_points);
    if (!values) {
      push_error(-104, "Data type error; expected 1..16384 comma-separated values");
      return true;
    }
    for (float f : *values)
      if (!(std::fabs(f) <= 1.0f)) {
        push_error(-222, "Data out of range; arbitrary values must lie in [-1, 1]");
        return true;
      }
    gen_.arb = std::move(*values);
  } else if (match("SOURce#:FREQuency:FIX", c.header, &sfx) && !c.query) {
    if (!channel_ok()) return true;
    if (!parse_one(c.params, &v) || v <= 0 || v > 62.5e6)
      push_error(-222, "Data out of range; frequency");
    else
      gen_.freq_hz = v;
  } else if (match("SOURce#:VOLTage:OFFSet", c.header, &sfx) && !c.query) {
    if (!channel_ok()) return true;
    if (!parse_one(c.params, &v) || std::fabs(v) + gen_.amplitude_v > 1.0)
      push_error(-222, "Data out of range; |amplitude| + |offset| must stay within 1 V");
    else
      gen_.offset_v = v;
  } else if (match("SOURce#:VOLTage", c.header, &sfx) && !c.query) {
    if (!channel_ok()) return true;
    if (!parse_one(c.params, &v) || v < 0 || v + std::fabs(gen_.offset_v) > 1.0)
      push_error(-222, "Data out of range; |amplitude| + |offset| must stay within 1 V");
    else
      gen_.amplitude_v = v;
  } else if (match("SOURce#:BURSt:STATe", c.header, &sfx) && !c.query) {
    if (!channel_ok()) return true;
    const std::string m = first(c.params);
    if (m != "BURST" && m != "CONTINUOUS")
      push_error(-224, "Illegal parameter value; BURST|CONTINUOUS");
    else
      gen_.burst = m == "BURST";
  } else if ((match("SOURce#:BURSt:NCYCles", c.header, &sfx) ||
              match("SOURce#:BURSt:NORepetitions", c.header, &sfx)) &&
             !c.query) {
    if (!channel_ok()) return true;
    const bool ncyc = upper(c.header).find("NCYC") != std::string::npos;
    if (!parse_one(c.params, &v) || v < 1 || v > 50000 || v != std::floor(v))
      push_error(-222, "Data out of range; burst count");
    else
      (ncyc ? gen_.cycles : gen_.repetitions) = static_cast<int>(v);
  } else if (match("SOURce#:TRig:SOURce", c.header, &sfx) && !c.query) {
    if (!channel_ok()) return true;
    if (first(c.params) != "INT")
      push_error(-224, "Illegal parameter value; the simulator offers INT only");
  } else if (match("SOURce#:TRig:INT", c.header, &sfx) && !c.query) {
    if (!channel_ok()) return true;
    fire();
  } else {
    return false;
  }
  return true;
}

bool SimRedPitaya::acquisition(const scpi::Command& c, Reply& out) {
  using scpi::match;
  std::vector<int> sfx;
  double v = 0;
  auto input_ok = [&] {
    if (!sfx.empty() && (sfx[0] == 1 || sfx[0] == 2)) return true;
    push_error(-114, "Header suffix out of range; inputs 1 and 2");
    return false;
  };
  if (match("ACQ:RST", c.header)) {
    acq_ = Acq{};  // as the server's RP_AcqReset: ASCII, VOLTS
    bench_->daq().codes[0].clear();
    bench_->daq().codes[1].clear();
  } else if (match("ACQ:DEC", c.header)) {
    if (c.query) {
      append(out, std::to_string(acq_.decimation) + "\r\n");
      return true;
    }
    bool known = false;
    if (parse_one(c.params, &v))
      for (unsigned d : rp::kDecimations) known = known || v == d;
    if (!known)
      push_error(-222, "Data out of range; decimation 1, 8, 64, 1024, 8192 or 65536");
    else
      acq_.decimation = static_cast<unsigned>(v);
  } else if (match("ACQ:DATA:FORMAT", c.header) && !c.query) {
    const std::string f = first(c.params);
    if (f != "BIN" && f != "ASCII")
      push_error(-224, "Illegal parameter value; BIN|ASCII");
    else
      acq_.binary = f == "BIN";
  } else if (match("ACQ:DATA:UNITS", c.header) && !c.query) {
    const std::string u = first(c.params);
    if (u != "VOLTS") push_error(-224, "Illegal parameter value; the simulator serves VOLTS only");
  } else if (match("ACQ:SOUR#:GAIN", c.header, &sfx)) {
    if (!input_ok()) return true;
    bool& hv = acq_.high_gain[sfx[0] - 1];
    if (c.query)
      append(out, hv ? "HV\r\n" : "LV\r\n");
    else if (first(c.params) == "LV" || first(c.params) == "HV")
      hv = first(c.params) == "HV";
    else
      push_error(-224, "Illegal parameter value; LV|HV");
  } else if (match("ACQ:TRig:DLY", c.header)) {
    if (c.query)
      append(out, std::to_string(acq_.delay) + "\r\n");
    else if (!parse_one(c.params, &v) || v != std::floor(v) || std::fabs(v) >= 8192)
      push_error(-222, "Data out of range; trigger delay (samples)");
    else
      acq_.delay = static_cast<long>(v);
  } else if (match("ACQ:START", c.header) && !c.query) {
    acq_.started = true;
    acq_.armed = false;
  } else if (match("ACQ:STOP", c.header) && !c.query) {
    acq_.started = acq_.armed = false;
  } else if (match("ACQ:TRig:STAT", c.header) && c.query) {
    append(out, acq_.armed ? "WAIT\r\n" : "TD\r\n");
  } else if (match("ACQ:TRig:FILL", c.header) && c.query) {
    append(out, acq_.armed ? "0\r\n" : "1\r\n");
  } else if (match("ACQ:TRig", c.header) && !c.query) {
    if (first(c.params) != "AWG_PE") {
      push_error(-224, "Illegal parameter value; the simulator wires AWG_PE only");
    } else if (!acq_.started) {
      push_error(-221, "Settings conflict; ACQ:START first");
    } else {
      acq_.armed = true;
      bench_->daq().codes[0].clear();
      bench_->daq().codes[1].clear();
      bench_->daq().done = false;
    }
  } else if (match("ACQ:SOUR#:DATA", c.header, &sfx) && c.query) {
    if (!input_ok()) return true;
    data_reply(sfx[0], out);
  } else {
    return false;
  }
  apply_acquisition_settings();
  return true;
}

bool SimRedPitaya::command(const scpi::Command& c, const scpi::ProgramMessage&, Reply& out) {
  std::lock_guard lock(bench_->mutex());
  if (c.header == "*RST") {
    gen_ = Gen{};
    acq_ = Acq{};
    apply_acquisition_settings();
    return true;
  }
  return generator(c, out) || acquisition(c, out);
}

}  // namespace piezo::drivers::sim
