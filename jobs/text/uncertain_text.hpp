#pragma once
// Numbers for people: a value with its standard uncertainty σ, σ rounded to two
// significant digits and the value rounded to the same decimal place (GUM 7.2.6),
// with its unit. Every human-readable print of a value ± σ goes through here
// (the CLI's text, the Markdown reports); JSON keeps the full numbers.
//
//   format_uncertain(13.6, 0.7139)              "13.60 ± 0.71"
//   format_uncertain(14846, 73.845, "pF")       "14846 ± 74 pF"
//   format_uncertain(4.808e-15, 1.6e-13, "F")   "(0.0 ± 1.6)e-13 F"
//   format_si(14846e-12, 73.845e-12, "F")       "14.846 ± 0.074 nF"
//   format_uncertain(50350, inf, "Hz")          "50350 Hz (σ not identifiable)"
//   format_uncertain(50350, inf, "Hz", {true})  "50350 ± — Hz"
//   format_uncertain(nan, 3)                    "—"
//   format_uncertain(2.5, 0)                    "2.5 ± 0 (exact)"
//
// Plain notation while the printed magnitudes stay between 1e-3 and 1e6 and σ
// needs at most 6 decimals; otherwise one common power of ten, "(m ± s)eE".
#include "dsp/uncertain_text.hpp"

namespace piezo::jobs {

// The implementation lives in dsp/uncertain_text (every layer prints alike).
using dsp::format_probability_log10;
using dsp::format_si;
using dsp::format_uncertain;
using dsp::format_value;
using dsp::UncertainStyle;

}  // namespace piezo::jobs
