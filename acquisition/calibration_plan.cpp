#include "acquisition/calibration_plan.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "drivers/keysight33500/driver.hpp"

namespace piezo::acq {

namespace {
std::string trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return std::string(s);
}
std::string num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.10g", v);
  return buf;
}
}  // namespace

std::vector<CalibrationStep> parse_calibration_list(std::string_view list, double load_ohm,
                                                    std::optional<double> load_parallel_f) {
  std::vector<CalibrationStep> out;
  if (trim(list).empty())
    throw std::invalid_argument("--calibrate: empty list (expected e.g. open,short,load)");
  std::size_t pos = 0;
  while (pos <= list.size()) {
    const std::size_t comma = list.find(',', pos);
    const std::string item =
        trim(list.substr(pos, comma == std::string_view::npos ? list.npos : comma - pos));
    const auto role = parse_role(item);
    if (!role || *role == Role::Dut)
      throw std::invalid_argument("--calibrate: unknown standard '" + item +
                                  "' (expected open, short or load)");
    for (const auto& s : out)
      if (s.role == *role)
        throw std::invalid_argument("--calibrate: standard '" + item + "' listed twice");
    CalibrationStep st;
    st.role = *role;
    if (*role == Role::Load) {
      if (!(std::isfinite(load_ohm) && load_ohm > 0))
        throw std::invalid_argument(
            "--load-ohm: the load standard's resistance must be positive, got " + num(load_ohm));
      if (load_parallel_f && !(std::isfinite(*load_parallel_f) && *load_parallel_f >= 0))
        throw std::invalid_argument("--load-parallel-f: must be >= 0, got " +
                                    num(*load_parallel_f));
      st.load_ohm = load_ohm;
      st.load_parallel_f = load_parallel_f;
    }
    out.push_back(st);
    if (comma == std::string_view::npos) break;
    pos = comma + 1;
  }
  return out;
}

std::string standard_instruction(const CalibrationStep& s) {
  switch (s.role) {
    case Role::Open:
      return "connect the OPEN standard: nothing at the transducer terminals (leads in place, "
             "unconnected)";
    case Role::Short:
      return "connect the SHORT standard: join the two transducer terminals with the shorting bar";
    case Role::Load:
      return "connect the LOAD standard: the " + num(s.load_ohm) + " ohm reference resistor" +
             (s.load_parallel_f && *s.load_parallel_f > 0
                  ? " (" + num(*s.load_parallel_f) + " F in parallel)"
                  : "") +
             " at the transducer terminals";
    case Role::Dut:
      break;
  }
  return "connect the TRANSDUCER under test to the terminals again";
}

double channel_range_for(const std::vector<double>& v, double max_range_v) {
  double peak = 0;
  for (double x : v) peak = std::max(peak, std::fabs(x));
  const double want = 1.5 * peak;
  for (double decade = 1e-3; decade < 1e3; decade *= 10)
    for (double m : {1.0, 2.0, 5.0}) {
      const double r = m * decade;
      if (r >= 5e-3 && r >= want) return std::min(r, max_range_v);
    }
  return max_range_v;
}

bool is_simulated_instrument(const Bench& bench) {
  return bench.awg && bench.awg->identity().find("piezobench-sim") != std::string::npos &&
         dynamic_cast<drivers::keysight33500::Driver*>(bench.awg.get()) != nullptr;
}

StandardConnector make_standard_connector(Bench& bench, TechnicianPrompt prompt) {
  if (is_simulated_instrument(bench)) {
    auto* awg = dynamic_cast<drivers::keysight33500::Driver*>(bench.awg.get());
    return [awg](const CalibrationStep& s) {
      std::string cmd = "SIMulation:DUT ";
      switch (s.role) {
        case Role::Open:
          cmd += "OPEN";
          break;
        case Role::Short:
          cmd += "SHORT";
          break;
        case Role::Load:
          cmd += "LOAD," + num(s.load_ohm) + "," + num(s.load_parallel_f.value_or(0.0));
          break;
        case Role::Dut:
          cmd += "TUBE";
          break;
      }
      awg->scpi().configure(cmd);  // *OPC? and SYST:ERR? after it: a refusal throws with its text
      return true;
    };
  }
  if (!prompt)
    throw std::invalid_argument(
        "calibration on a real bench needs a technician to connect the standards: no prompt was "
        "given");
  return [prompt](const CalibrationStep& s) { return prompt(standard_instruction(s)); };
}

}  // namespace piezo::acq
