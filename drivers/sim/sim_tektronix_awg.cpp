#include "drivers/sim/sim_tektronix_awg.hpp"

#include <cmath>
#include <cstdlib>
#include <stdexcept>

#include "drivers/sim/scpi_args.hpp"

namespace piezo::drivers::sim {

namespace tek = piezo::drivers::tektronix_awg;

namespace {
bool is_on(const std::vector<std::string>& p) {
  return !p.empty() && (upper(p[0]) == "ON" || p[0] == "1");
}
// A <string> parameter: "name" or 'name'; false if unquoted or empty.
bool unquote(const std::string& p, std::string* out) {
  if (p.size() < 2 || (p.front() != '"' && p.front() != '\'') || p.back() != p.front())
    return false;
  *out = p.substr(1, p.size() - 2);
  return !out->empty();
}
std::string num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.10g", v);
  return buf;
}
const tek::Model& sim_model() {
  for (const auto& m : tek::kModels)
    if (m.idn_model == "AWG5014C") return m;
  throw std::logic_error("SimTektronixAwg: AWG5014C missing from the model table");
}
constexpr double kMarkerMinV = -1.0, kMarkerMaxV = 2.7;  // AWG5000 marker window into 50 ohm
}  // namespace

SimTektronixAwg::SimTektronixAwg(std::shared_ptr<SimBench> bench)
    : bench_(std::move(bench)), model_(sim_model()) {
  if (!bench_) throw std::invalid_argument("SimTektronixAwg: null bench");
  reset();
}

void SimTektronixAwg::reset() {
  s_ = State{};
  list_.clear();
  order_.clear();
  Waveform dc{std::vector<float>(1000, 0.0f), std::vector<std::uint8_t>(1000, 0), true};
  Waveform sine{std::vector<float>(100), std::vector<std::uint8_t>(100, 0), true};
  for (std::size_t i = 0; i < 100; ++i)
    sine.values[i] = static_cast<float>(std::sin(2 * M_PI * i / 100.0));
  for (auto& [name, w] : {std::pair{"*DC", dc}, std::pair{"*Sine100", sine}}) {
    list_[name] = w;
    order_.push_back(name);
  }
}

// A trigger plays channel 1's waveform once: the bench is fed the generator's
// EMF (twice the 50-ohm levels) and fires if marker 1 rises with point 0.
void SimTektronixAwg::trigger() {
  if (s_.run_state != 1) {
    push_error(-211, "Trigger ignored; not waiting for a trigger");
    return;
  }
  const Waveform& w = list_.at(s_.assigned);
  AwgState& a = bench_->awg();
  a.arb = w.values;
  a.arb_rate_hz = s_.sample_rate_hz;
  a.vpp = 2.0 * s_.amplitude_vpp;
  a.offset_v = 2.0 * s_.offset_v;
  a.output_on = s_.output_on;
  const bool edge =
      !w.markers.empty() && (w.markers[0] & tek::kMarker1Bit) && s_.marker_high_v > s_.marker_low_v;
  if (edge) bench_->fire();
}

bool SimTektronixAwg::waveform_list(const scpi::Command& c, const scpi::ProgramMessage& msg,
                                    Reply& out) {
  using scpi::match;
  std::vector<std::string> p = c.params;
  while (!p.empty() && p.back().empty()) p.pop_back();  // "name,0,N," before a block
  std::string name;
  double v = 0;
  if (match("WLISt:SIZE", c.header) && c.query) {
    append(out, std::to_string(order_.size()) + "\n");
  } else if (match("WLISt:NAME", c.header) && c.query) {
    if (!parse_one(p, &v) || v < 0 || v >= static_cast<double>(order_.size()) ||
        v != std::floor(v)) {
      push_error(-222, "Data out of range; waveform list index");
      append(out, "\"\"\n");
    } else {
      append(out, "\"" + order_[static_cast<std::size_t>(v)] + "\"\n");
    }
  } else if (match("WLISt:WAVeform:NEW", c.header) && !c.query) {
    if (p.size() != 3 || !unquote(p[0], &name) || !parse_number(p[1], &v)) {
      push_error(-109, "Missing parameter; WLIST:WAVEFORM:NEW \"name\",<size>,REAL");
    } else if (list_.count(name)) {
      push_error(-224, "Illegal parameter value; waveform \"" + name + "\" already exists");
    } else if (v != std::floor(v) || v < static_cast<double>(model_.min_points) ||
               v > static_cast<double>(model_.max_points)) {
      push_error(-222, "Data out of range; waveform size");
    } else if (!upper(p[2]).starts_with("REAL")) {
      push_error(-224, "Illegal parameter value; the simulator serves REAL waveforms only");
    } else {
      const auto n = static_cast<std::size_t>(v);
      list_[name] = Waveform{std::vector<float>(n, 0.0f), std::vector<std::uint8_t>(n, 0), false};
      order_.push_back(name);
    }
  } else if (match("WLISt:WAVeform:DATA", c.header) && !c.query) {
    if (!msg.has_block || p.empty() || p.size() > 3 || !unquote(p[0], &name)) {
      push_error(-104, "Data type error; expected \"name\"[,<start>[,<size>]],<block>");
      return true;
    }
    auto it = list_.find(name);
    if (it == list_.end() || it->second.predefined) {
      push_error(-224, "Illegal parameter value; no user waveform \"" + name + "\"");
      return true;
    }
    auto pts = tek::decode_real_points(msg.block);
    double start = 0, size = pts ? static_cast<double>(pts->values.size()) : 0;
    if (!pts || (p.size() >= 2 && !parse_number(p[1], &start)) ||
        (p.size() == 3 && !parse_number(p[2], &size))) {
      push_error(-104, "Data type error; REAL data is 5 bytes per point");
      return true;
    }
    Waveform& w = it->second;
    if (size != static_cast<double>(pts->values.size()) || start < 0 ||
        start != std::floor(start) || start + size > static_cast<double>(w.values.size())) {
      push_error(-222, "Data out of range; start/size do not fit the block or the waveform");
      return true;
    }
    for (float f : pts->values)
      if (!(std::fabs(f) <= 1.0f)) {
        push_error(-222, "Data out of range; REAL values must lie in [-1, 1]");
        return true;
      }
    const auto s0 = static_cast<std::size_t>(start);
    std::copy(pts->values.begin(), pts->values.end(),
              w.values.begin() + static_cast<std::ptrdiff_t>(s0));
    std::copy(pts->markers.begin(), pts->markers.end(),
              w.markers.begin() + static_cast<std::ptrdiff_t>(s0));
  } else if (match("WLISt:WAVeform:DELete", c.header) && !c.query) {
    auto it = p.size() == 1 && unquote(p[0], &name) ? list_.find(name) : list_.end();
    if (it == list_.end() || it->second.predefined) {
      push_error(-224, "Illegal parameter value; no user waveform to delete");
    } else {
      list_.erase(it);
      std::erase(order_, name);
      if (s_.assigned == name) {  // unloaded: the run stops, the channel switches off
        s_.assigned.clear();
        s_.run_state = 0;
        s_.output_on = false;
      }
    }
  } else if (match("WLISt:WAVeform:LENGth", c.header) && c.query) {
    auto it = p.size() == 1 && unquote(p[0], &name) ? list_.find(name) : list_.end();
    if (it == list_.end()) push_error(-224, "Illegal parameter value; no such waveform");
    append(out, std::to_string(it == list_.end() ? 0 : it->second.values.size()) + "\n");
  } else {
    return false;
  }
  return true;
}

bool SimTektronixAwg::source(const scpi::Command& c, Reply& out) {
  using scpi::match;
  std::vector<int> sfx;
  double v = 0;
  std::string name;
  auto channel_ok = [&] {
    if (!sfx.empty() && sfx[0] == 1) return true;
    push_error(-114, "Header suffix out of range; the simulator wires channel 1 only");
    return false;
  };
  if (match("[SOURce#:]WAVeform", c.header, &sfx)) {
    if (!channel_ok()) return true;
    if (c.query) {
      append(out, "\"" + s_.assigned + "\"\n");
    } else if (c.params.size() != 1 || !unquote(c.params[0], &name) || !list_.count(name)) {
      push_error(-224, "Illegal parameter value; no such waveform in the list");
    } else {
      s_.assigned = name;
    }
  } else if (match("[SOURce#:]FREQuency[:CW]", c.header, &sfx) ||
             match("[SOURce#:]FREQuency:FIXed", c.header, &sfx)) {
    if (c.query)
      append(out, num(s_.sample_rate_hz) + "\n");
    else if (!parse_one(c.params, &v) || v < model_.min_sample_rate_hz ||
             v > model_.max_sample_rate_hz)
      push_error(-222, "Data out of range; sampling frequency");
    else
      s_.sample_rate_hz = v;
  } else if (match("[SOURce#:]DAC:RESolution", c.header, &sfx)) {
    if (!channel_ok()) return true;
    if (c.query)
      append(out, std::to_string(model_.dac_bits) + "\n");
    else if (!parse_one(c.params, &v) || v != model_.dac_bits)
      push_error(-222, "Data out of range; DAC resolution");
  } else if (match("[SOURce#:]VOLTage[:LEVel][:IMMediate]:OFFSet", c.header, &sfx)) {
    if (!channel_ok()) return true;
    if (c.query)
      append(out, num(s_.offset_v) + "\n");
    else if (!parse_one(c.params, &v) || std::fabs(v) > model_.max_offset_v)
      push_error(-222, "Data out of range; offset");
    else
      s_.offset_v = v;
  } else if (match("[SOURce#:]VOLTage[:LEVel][:IMMediate][:AMPLitude]", c.header, &sfx)) {
    if (!channel_ok()) return true;
    if (c.query)
      append(out, num(s_.amplitude_vpp) + "\n");
    else if (!parse_one(c.params, &v) || v < model_.min_amplitude_vpp ||
             v > model_.max_amplitude_vpp)
      push_error(-222, "Data out of range; amplitude");
    else
      s_.amplitude_vpp = v;
  } else if (match("[SOURce#:]MARKer#:VOLTage[:LEVel][:IMMediate]:HIGH", c.header, &sfx) ||
             match("[SOURce#:]MARKer#:VOLTage[:LEVel][:IMMediate]:LOW", c.header, &sfx)) {
    if (!channel_ok()) return true;
    const bool high = upper(c.header).ends_with("HIGH");
    double& level = high ? s_.marker_high_v : s_.marker_low_v;
    const bool marker1 = sfx.size() > 1 && sfx[1] == 1;
    if (c.query)
      append(out, num(marker1 ? level : 0.0) + "\n");
    else if (!parse_one(c.params, &v) || v < kMarkerMinV || v > kMarkerMaxV)
      push_error(-222, "Data out of range; marker level");
    else if (marker1)
      level = v;  // marker 2 is not wired to anything
  } else if (match("[SOURce#:]MARKer#:DELay", c.header, &sfx)) {
    // 0..1 ns on the AWG5000: far below a DAQ sample period here; accepted, not modelled.
    if (!channel_ok()) return true;
    if (c.query)
      append(out, "0\n");
    else if (!parse_one(c.params, &v) || v < 0 || v > 1e-9)
      push_error(-222, "Data out of range; marker delay");
  } else if (match("OUTPut#[:STATe]", c.header, &sfx)) {
    if (!channel_ok()) return true;
    if (c.query)
      append(out, s_.output_on ? "1\n" : "0\n");
    else
      s_.output_on = is_on(c.params);
  } else {
    return false;
  }
  return true;
}

bool SimTektronixAwg::command(const scpi::Command& c, const scpi::ProgramMessage& msg, Reply& out) {
  using scpi::match;
  std::lock_guard lock(bench_->mutex());
  if (c.header == "*RST") {
    reset();
  } else if (c.header == "*TRG" ||
             (match("TRIGger[:SEQuence][:IMMediate]", c.header) && !c.query)) {
    trigger();
  } else if (match("TRIGger[:SEQuence]:SOURce", c.header)) {
    if (c.query)
      append(out, s_.external_trigger ? "EXT\n" : "INT\n");
    else if (c.params.size() == 1 && upper(c.params[0]).starts_with("EXT"))
      s_.external_trigger = true;
    else if (c.params.size() == 1 && upper(c.params[0]).starts_with("INT"))
      s_.external_trigger = false;
    else
      push_error(-224, "Illegal parameter value; INTernal|EXTernal");
  } else if (match("AWGControl:RMODe", c.header)) {
    if (c.query) {
      append(out, s_.triggered_mode ? "TRIG\n" : "CONT\n");
    } else if (c.params.size() == 1 && upper(c.params[0]).starts_with("TRIG")) {
      s_.triggered_mode = true;
    } else if (c.params.size() == 1 && upper(c.params[0]).starts_with("CONT")) {
      s_.triggered_mode = false;
    } else {
      push_error(-224, "Illegal parameter value; the simulator offers CONTinuous and TRIGgered");
      return true;
    }
    if (s_.run_state != 0) s_.run_state = s_.triggered_mode ? 1 : 2;
  } else if (match("AWGControl:RUN[:IMMediate]", c.header) && !c.query) {
    if (s_.assigned.empty())
      push_error(-221, "Settings conflict; no waveform assigned to channel 1");
    else
      s_.run_state = s_.triggered_mode ? 1 : 2;
  } else if (match("AWGControl:STOP[:IMMediate]", c.header) && !c.query) {
    s_.run_state = 0;
  } else if (match("AWGControl:RSTate", c.header) && c.query) {
    append(out, std::to_string(s_.run_state) + "\n");
  } else if (!waveform_list(c, msg, out) && !source(c, out)) {
    return false;
  }
  return true;
}

}  // namespace piezo::drivers::sim
