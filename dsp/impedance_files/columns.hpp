#pragma once
// The meaning of one column header of an impedance table, from its words and
// its unit: "f_hz", "Frequency(Hz)", "Frequency (Hz)", "|Z|(Ohm)-data",
// "theta-z(deg)-data", "Trace 1: Impedance: Real (Ω)", "re_ohm", "G (mS)",
// "Phase [rad]", "Cp(F)-data", "S11(REAL)", "abs_sigma_ohm", ...
//   units:  Hz kHz MHz GHz (any case); Ω/ohm with m k M G prefixes (mΩ milli,
//           MΩ mega); S with m u µ n p prefixes; deg ° rad; dB; H and F with
//           prefixes; U or () for a pure number.
//   S21:    "S21(DB)", "Transmission Loss(dB)" (vna/J, transmission mode)
//   ignored: memory traces ("-mem", "Memory"), quantities that are not an
//           impedance (gain, S21, return loss, voltage, current, ...), and
//           names that say nothing we know.
#include <string>
#include <string_view>
#include <vector>

#include "dsp/impedance_files/quantities.hpp"

namespace piezo::dsp::zfiles {

enum class Role { Ignored, Frequency, Value, SigmaMag, SigmaPhase, Coverage };

struct ColumnMeaning {
  Role role = Role::Ignored;
  Quantity quantity = Quantity::Unknown;  // Unknown: fits a partner of either
  Part part = Part::None;
  double scale = 1.0;       // file unit -> Hz, ohm, S, rad, H, F (dB values stay dB)
  bool unit_given = false;  // false: Hz, ohm/S, degrees assumed
  std::string why;          // why a column is ignored
  bool loss = false;        // "Transmission Loss(dB)": a loss, maybe written positive
};

ColumnMeaning classify_column(std::string_view header);

// The names of a table's columns as the user gives them (`piezobench figures
// --columns f[kHz],G[uS],B[uS]`): a comma list of header names as above, each
// with its unit in brackets; "-" or "skip" leaves a column out, a leading "-"
// negates one ("-theta(deg)": a current's phase read as the impedance's). Throws
// std::invalid_argument naming an item that is no column we know, or a list
// without a frequency.
std::vector<std::string> parse_column_spec(std::string_view spec);

}  // namespace piezo::dsp::zfiles
