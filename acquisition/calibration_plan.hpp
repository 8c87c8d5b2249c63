#pragma once
// Fixture calibration standards measured before the DUT shots of a capture
// (open, short, load; capture-format.md: the shots' `role` attribute), and how
// each gets connected: the simulator swaps its device itself (SIM:DUT), on a
// real bench the technician is asked (terminal prompt, GUI dialog).
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "acquisition/bench.hpp"
#include "acquisition/capture.hpp"

namespace piezo::acq {

struct CalibrationStep {
  Role role = Role::Open;                 // Open, Short, Load; Dut = the transducer back in place
  double load_ohm = 0.0;                  // Load: the standard's resistance
  std::optional<double> load_parallel_f;  // Load: its parallel capacitance (absent = 0)
};

// "open,short,load" (any subset, any order, no repeats) → steps. Throws
// std::invalid_argument naming the bad item.
std::vector<CalibrationStep> parse_calibration_list(
    std::string_view list, double load_ohm = 1000.0,
    std::optional<double> load_parallel_f = std::nullopt);

// What the technician must do for a step, e.g. "connect the SHORT standard (terminals joined)".
std::string standard_instruction(const CalibrationStep& step);

// Connects a standard (or, for role Dut, the transducer again) before its
// shots; returns false when the operator cancelled. Throws on failure.
using StandardConnector = std::function<bool(const CalibrationStep&)>;

// Asks a person: shows the instruction, returns false to cancel.
using TechnicianPrompt = std::function<bool(const std::string& instruction)>;

// The connector for a bench: a simulated instrument (in-process or the
// sim-instrument server, recognised by its *IDN?) swaps the device itself with
// the simulator-only SCPI command SIM:DUT over the AWG's own connection; any
// other bench asks the technician through `prompt` (required then).
StandardConnector make_standard_connector(Bench& bench, TechnicianPrompt prompt);

// The DAQ range (±V) for a channel whose recorded signal is `v`: the smallest
// 1-2-5 step >= 1.5 × its peak, at least 5 mV, at most `max_range_v`.
double channel_range_for(const std::vector<double>& v, double max_range_v);

// True when the bench's AWG is the piezobench simulator (it understands SIM:DUT).
bool is_simulated_instrument(const Bench& bench);

}  // namespace piezo::acq
