#pragma once
// Numbers for people: a value with its standard uncertainty σ, σ rounded to two
// significant digits and the value rounded to the same decimal place (GUM 7.2.6),
// with its unit. Every human-readable print of a value ± σ goes through here
// (the CLI's text, the Markdown reports, the diagnosis' sentences); JSON keeps the
// full numbers. In dsp/ so that every layer prints alike (jobs/text/uncertain_text.hpp
// brings these names into piezo::jobs).
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
#include <string>
#include <string_view>

namespace piezo::dsp {

struct UncertainStyle {
  // Compact (table cells): a σ that is not finite prints as "± —" instead of
  // "(σ not identifiable)".
  bool compact = false;
  // Significant digits of a value printed without a usable σ.
  int bare_digits = 6;
  // What a σ that is not finite says (prose style).
  const char* no_sigma = "σ not identifiable";
  // What a value or a compact σ that is not finite prints as ("—"; the GUI's
  // font, Latin-1 only, takes "-").
  const char* dash = "\xE2\x80\x94";
};

std::string format_uncertain(double value, double sigma, std::string_view unit = {},
                             const UncertainStyle& style = {});

// The same with the SI prefix (f p n µ m – k M G) chosen from the larger of
// |value| and σ when `base_unit` is an unprefixed SI unit (F, H, Hz, s, V, A, W,
// m, ohm, Ω); any other unit is printed as format_uncertain does.
std::string format_si(double value, double sigma, std::string_view base_unit,
                      const UncertainStyle& style = {});

// A value without σ, `digits` significant digits, with its unit; "—" when not finite.
std::string format_value(double value, std::string_view unit = {}, int digits = 6);

// A probability given by its log10 (it may lie far below what a double holds):
// "1e-12", "3.2e-5", "0.27"; below 1e-300 "< 1e-300".
std::string format_probability_log10(double log10_p);

}  // namespace piezo::dsp
