#include "drivers/sim/sim_awg.hpp"

#include <cmath>
#include <cstdlib>
#include <cstring>

namespace piezo::drivers::sim {

namespace {
bool parse_num(const std::vector<std::string>& p, double* v) {
  if (p.size() != 1) return false;
  char* end = nullptr;
  *v = std::strtod(p[0].c_str(), &end);
  return end != p[0].c_str() && std::isfinite(*v);
}
bool is_on(const std::vector<std::string>& p) { return !p.empty() && (p[0] == "ON" || p[0] == "1"); }
std::string upper(std::string s) {
  for (auto& ch : s) ch = static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
  return s;
}
}  // namespace

bool SimAwg::command(const scpi::Command& c, const scpi::ProgramMessage& msg, Reply&) {
  using scpi::match;
  std::lock_guard lock(bench_->mutex());
  AwgState& a = bench_->awg();
  double v = 0;
  if (c.header == "*RST") {
    a = AwgState{};
    volatile_.clear();
  } else if (c.header == "*TRG") {
    if (!a.bus_trigger) push_error(-211, "Trigger ignored");
    else bench_->fire();
  } else if (match("FORMat:BORDer", c.header) && !c.query) {
    swapped_ = !c.params.empty() && upper(c.params[0]).starts_with("SWAP");
  } else if (match("[SOURce#:]DATA:VOLatile:CLEar", c.header)) {
    volatile_.clear();
  } else if (match("[SOURce#:]DATA:ARBitrary", c.header) && !c.query) {
    if (!msg.has_block || c.params.empty() || msg.block.size() % 4 != 0 || msg.block.size() < 32) {
      push_error(-104, "Data type error; expected name,<float32 block>");
      return true;
    }
    if (!swapped_) {
      push_error(-221, "Settings conflict; set FORMat:BORDer SWAPped for this host");
      return true;
    }
    std::vector<float> s(msg.block.size() / 4);
    std::memcpy(s.data(), msg.block.data(), msg.block.size());
    for (float f : s)
      if (!(std::fabs(f) <= 1.0f)) {
        push_error(-222, "Data out of range; arb values must be in [-1, 1]");
        return true;
      }
    std::string name = upper(c.params[0]);
    while (!name.empty() && (name.back() == '#' || name.back() == ' ')) name.pop_back();
    volatile_[name] = std::move(s);
  } else if (match("[SOURce#:]FUNCtion:ARBitrary:SRATe", c.header) && !c.query) {
    if (!parse_num(c.params, &v) || v <= 0 || v > 250e6) push_error(-222, "Data out of range");
    else a.arb_rate_hz = v;
  } else if (match("[SOURce#:]FUNCtion:ARBitrary", c.header) && !c.query) {
    auto it = c.params.empty() ? volatile_.end() : volatile_.find(upper(c.params[0]));
    if (it == volatile_.end()) push_error(-224, "Illegal parameter value; no such arb");
    else a.arb = it->second;
  } else if (match("[SOURce#:]FUNCtion", c.header) && !c.query) {
    if (c.params.empty() || !upper(c.params[0]).starts_with("ARB"))
      push_error(-224, "Illegal parameter value; the simulator offers ARB only");
  } else if (match("[SOURce#:]VOLTage:OFFSet", c.header) && !c.query) {
    if (!parse_num(c.params, &v)) push_error(-104, "Data type error");
    else a.offset_v = v;
  } else if (match("[SOURce#:]VOLTage[:AMPLitude]", c.header) && !c.query) {
    if (!parse_num(c.params, &v) || v <= 0 || v > 20) push_error(-222, "Data out of range");
    else a.vpp = v;
  } else if (match("OUTPut#:LOAD", c.header) || match("OUTPut:SYNC", c.header) ||
             match("[SOURce#:]BURSt:MODE", c.header) || match("[SOURce#:]BURSt:NCYCles", c.header)) {
    // accepted; the simulator's behaviour is the configured one
  } else if (match("[SOURce#:]BURSt:STATe", c.header) && !c.query) {
    a.burst_on = is_on(c.params);
  } else if (match("TRIGger#:SOURce", c.header) && !c.query) {
    a.bus_trigger = !c.params.empty() && upper(c.params[0]) == "BUS";
  } else if (match("OUTPut#[:STATe]", c.header) && !c.query) {
    a.output_on = is_on(c.params);
  } else {
    return false;
  }
  return true;
}

}  // namespace piezo::drivers::sim
