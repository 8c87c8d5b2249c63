#include "drivers/sim/sim_daq.hpp"

#include <cmath>
#include <cstdlib>
#include <cstring>

#include "drivers/ieee488_block.hpp"
#include "drivers/sim/scpi_args.hpp"

namespace piezo::drivers::sim {

namespace {
std::string num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}
}  // namespace

void SimDaq::waveform_data(Reply& out) {
  DaqState& d = bench_->daq();
  const auto& codes = d.codes[source_ - 1];
  std::vector<std::uint8_t> payload(codes.size() * 2);
  std::memcpy(payload.data(), codes.data(), payload.size());  // little-endian host = LSBFirst
  std::string head = block_header(payload.size());
  const int shot = bench_->acquisitions() - 1;
  const auto& f = bench_->faults();
  const bool fault_here = f.at_shot == shot && source_ == 2;
  using K = FaultPlan::Kind;
  if (fault_here && f.kind == K::NoReplyToFetch) {
    out.swallow = true;
    return;
  }
  if (fault_here && f.kind == K::MalformedBlock) head = "#X" + head.substr(2);
  append(out, head);
  if (fault_here && (f.kind == K::CloseMidFetch || f.kind == K::TruncatedBlock)) {
    out.bytes.insert(out.bytes.end(), payload.begin(), payload.begin() + static_cast<std::ptrdiff_t>(payload.size() / 3));
    out.close_connection = true;  // a truncated block ends with the link going down
    return;
  }
  out.bytes.insert(out.bytes.end(), payload.begin(), payload.end());
  append(out, "\n");
}

bool SimDaq::command(const scpi::Command& c, const scpi::ProgramMessage&, Reply& out) {
  using scpi::match;
  std::lock_guard lock(bench_->mutex());
  DaqState& d = bench_->daq();
  if (d.done) {  // latch the event for :ADER?
    ader_ = true;
    d.done = false;
  }
  double v = 0;
  std::vector<int> sfx;
  const auto& f = bench_->faults();
  if (!c.query && c.header != "*RST" && f.kind == FaultPlan::Kind::ErrorOnConfigure &&
      bench_->acquisitions() == f.at_shot && match(":ACQuire:POINts[:ANALog]", c.header)) {
    push_error(-222, "Data out of range; simulated fault");
    return true;
  }
  if (c.header == "*RST") {
    d = DaqState{};
  } else if (match("SYSTem:HEADer", c.header) || match("ACQuire:MODE", c.header) ||
             match("TIMebase:REFerence", c.header) || match("TRIGger:MODE", c.header) ||
             match("TRIGger:EDGE:SLOPe", c.header) || match("WAVeform:STReaming", c.header) ||
             match("CHANnel#:DISPlay", c.header, &sfx) || match("CHANnel#:INPut", c.header, &sfx) ||
             match("CHANnel#:OFFSet", c.header, &sfx)) {
    // accepted
  } else if (match("ACQuire:SRATe[:ANALog]", c.header)) {
    if (c.query) append(out, num(d.sample_rate_hz) + "\n");
    else if (!parse_one(c.params, &v) || v <= 0 || v > 20e9) push_error(-222, "Data out of range");
    else d.sample_rate_hz = v;
  } else if (match("ACQuire:POINts[:ANALog]", c.header)) {
    if (c.query) append(out, std::to_string(d.points) + "\n");
    else if (!parse_one(c.params, &v) || v < 16 || v > 10e6) push_error(-222, "Data out of range");
    else d.points = static_cast<std::size_t>(v);
  } else if (match("CHANnel#:RANGe", c.header, &sfx)) {
    int ch = sfx.empty() ? 1 : sfx[0];
    if (ch < 1 || ch > 2) push_error(-114, "Header suffix out of range");
    else if (c.query) append(out, num(d.full_scale_v[ch - 1]) + "\n");
    else if (!parse_one(c.params, &v) || v <= 0 || v > 40) push_error(-222, "Data out of range");
    else d.full_scale_v[ch - 1] = v;
  } else if (match("TIMebase:POSition", c.header)) {
    if (c.query) append(out, num(d.position_s) + "\n");
    else if (!parse_one(c.params, &v)) push_error(-104, "Data type error");
    else d.position_s = v;
  } else if (match("TRIGger:EDGE:SOURce", c.header) && !c.query) {
    d.aux_trigger = !c.params.empty() && upper(c.params[0]) == "AUX";
  } else if (match("SINGle", c.header)) {
    d.armed = true;
    d.done = false;
    ader_ = false;
  } else if (match("ADER", c.header) && c.query) {
    append(out, ader_ ? "1\n" : "0\n");
    ader_ = false;
  } else if (match("WAVeform:SOURce", c.header) && !c.query) {
    std::vector<int> s;
    if (c.params.empty() || !match("CHANnel#", c.params[0], &s) || s.empty() || s[0] < 1 || s[0] > 2)
      push_error(-224, "Illegal parameter value");
    else source_ = s[0];
  } else if (match("WAVeform:FORMat", c.header) && !c.query) {
    word_ = !c.params.empty() && upper(c.params[0]) == "WORD";
  } else if (match("WAVeform:BYTeorder", c.header) && !c.query) {
    lsb_first_ = !c.params.empty() && upper(c.params[0]).starts_with("LSBF");
  } else if (match("WAVeform:YINCrement", c.header) && c.query) {
    append(out, num(d.yincrement[source_ - 1]) + "\n");
  } else if (match("WAVeform:YORigin", c.header) && c.query) {
    append(out, "0\n");
  } else if (match("WAVeform:XINCrement", c.header) && c.query) {
    append(out, num(1.0 / d.sample_rate_hz) + "\n");
  } else if (match("WAVeform:POINts", c.header) && c.query) {
    append(out, std::to_string(d.codes[source_ - 1].size()) + "\n");
  } else if (match("WAVeform:DATA", c.header) && c.query) {
    if (!word_ || !lsb_first_) {
      push_error(-221, "Settings conflict; the simulator serves WORD, LSBFirst");
      append(out, "#10\n");
    } else if (d.codes[source_ - 1].empty()) {
      push_error(-230, "Data corrupt or stale; no acquisition");
      append(out, "#10\n");
    } else {
      waveform_data(out);
    }
  } else {
    return false;
  }
  return true;
}

}  // namespace piezo::drivers::sim
