#include "drivers/sim/sim_awg.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "drivers/sim/scpi_args.hpp"

namespace piezo::drivers::sim {

namespace {
bool is_on(const std::vector<std::string>& p) { return !p.empty() && (p[0] == "ON" || p[0] == "1"); }
}  // namespace

// SIMulation:DUT TUBE | OPEN | SHORT | LOAD,<ohm>[,<farad>]   (simulator only)
// SIMulation:DUT?  →  TUBE | OPEN | SHORT | LOAD,<ohm>,<farad>
// Swaps what sits at the transducer terminals; the fixture stays. A real
// 33500 answers -113 (undefined header), so only the simulator is sent this.
void SimAwg::sim_dut(const scpi::Command& c, Reply& out) {
  using K = DutSelection::Kind;
  if (c.query) {
    const auto& d = bench_->dut();
    const char* names[] = {"TUBE", "OPEN", "SHORT", "LOAD"};
    std::string r = names[static_cast<int>(d.kind)];
    if (d.kind == K::Load) {
      char buf[80];
      std::snprintf(buf, sizeof buf, ",%.10g,%.10g", d.load_ohm, d.load_parallel_f);
      r += buf;
    }
    append(out, r + "\n");
    return;
  }
  DutSelection d;
  const std::string kind = c.params.empty() ? std::string() : upper(c.params[0]);
  if (kind == "TUBE" || kind == "DUT") d.kind = K::Tube;
  else if (kind == "OPEN") d.kind = K::Open;
  else if (kind == "SHORT") d.kind = K::Short;
  else if (kind == "LOAD") d.kind = K::Load;
  else {
    push_error(-224, "Illegal parameter value; SIM:DUT TUBE|OPEN|SHORT|LOAD,<ohm>[,<farad>]");
    return;
  }
  const std::size_t want = d.kind == K::Load ? 2 : 1;
  if (c.params.size() < want || c.params.size() > (d.kind == K::Load ? 3u : 1u)) {
    push_error(-109, d.kind == K::Load ? "Missing parameter; SIM:DUT LOAD,<ohm>[,<farad>]"
                                       : "Parameter not allowed; SIM:DUT TUBE|OPEN|SHORT takes no value");
    return;
  }
  if (d.kind == K::Load) {
    double v = 0;
    if (!parse_one({c.params[1]}, &v)) {
      push_error(-104, "Data type error; load resistance");
      return;
    }
    d.load_ohm = v;
    if (c.params.size() == 3) {
      if (!parse_one({c.params[2]}, &v)) {
        push_error(-104, "Data type error; load capacitance");
        return;
      }
      d.load_parallel_f = v;
    }
  }
  const std::string why = bench_->select_dut(d);
  if (!why.empty()) push_error(-222, "Data out of range; " + why);
}

bool SimAwg::command(const scpi::Command& c, const scpi::ProgramMessage& msg, Reply& out) {
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
    if (!parse_one(c.params, &v) || v <= 0 || v > 250e6) push_error(-222, "Data out of range");
    else a.arb_rate_hz = v;
  } else if (match("[SOURce#:]FUNCtion:ARBitrary", c.header) && !c.query) {
    auto it = c.params.empty() ? volatile_.end() : volatile_.find(upper(c.params[0]));
    if (it == volatile_.end()) push_error(-224, "Illegal parameter value; no such arb");
    else a.arb = it->second;
  } else if (match("[SOURce#:]FUNCtion", c.header) && !c.query) {
    if (c.params.empty() || !upper(c.params[0]).starts_with("ARB"))
      push_error(-224, "Illegal parameter value; the simulator offers ARB only");
  } else if (match("[SOURce#:]VOLTage:OFFSet", c.header) && !c.query) {
    if (!parse_one(c.params, &v)) push_error(-104, "Data type error");
    else a.offset_v = v;
  } else if (match("[SOURce#:]VOLTage[:AMPLitude]", c.header) && !c.query) {
    if (!parse_one(c.params, &v) || v <= 0 || v > 20) push_error(-222, "Data out of range");
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
  } else if (match("SIMulation:DUT", c.header)) {
    sim_dut(c, out);
  } else {
    return false;
  }
  return true;
}

}  // namespace piezo::drivers::sim
