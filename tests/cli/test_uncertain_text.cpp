// Issue 41 item 7: value ± σ as printed (jobs/text/uncertain_text.hpp) — σ to two
// significant digits, the value rounded to the same place, a unit, never inf or
// nan as a σ; and item 6: error messages without the libraries' internal
// function names (jobs/text/user_message.hpp), the list of those names kept in
// step with the sources.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <regex>
#include <set>
#include <string>

#include "jobs/text/uncertain_text.hpp"
#include "jobs/text/user_message.hpp"

using piezo::jobs::format_probability_log10;
using piezo::jobs::format_si;
using piezo::jobs::format_uncertain;
using piezo::jobs::format_value;
using piezo::jobs::user_message;

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}  // namespace

TEST(UncertainText, SigmaToTwoSignificantDigitsAndTheValueToMatch) {
  // The issue's examples.
  EXPECT_EQ(format_uncertain(13.6, 0.7139), "13.60 ± 0.71");
  EXPECT_EQ(format_uncertain(14846, 73.845, "pF"), "14846 ± 74 pF");
  // σ above 10: the value rounded to σ's last kept digit (tens here).
  EXPECT_EQ(format_uncertain(14846, 734, "pF"), "14850 ± 730 pF");
  EXPECT_EQ(format_uncertain(0.31, 0.0012), "0.3100 ± 0.0012");
  EXPECT_EQ(format_uncertain(33.32, 0.79, "ohm"), "33.32 ± 0.79 ohm");
  // σ rounding up a place: 0.996 -> 1.0 (two digits, one place up), the value with it.
  EXPECT_EQ(format_uncertain(99.96, 0.996), "100.0 ± 1.0");
  EXPECT_EQ(format_uncertain(5.0, 0.0995), "5.00 ± 0.10");
}

TEST(UncertainText, NegativeValuesAndValuesThatRoundToZero) {
  EXPECT_EQ(format_uncertain(-2.5, 0.31, "V"), "-2.50 ± 0.31 V");
  EXPECT_EQ(format_uncertain(-0.004, 0.16), "0.00 ± 0.16");  // no "-0.00"
  EXPECT_EQ(format_uncertain(-0.132, 0.012), "-0.132 ± 0.012");
}

TEST(UncertainText, VerySmallAndVeryLargeMagnitudesShareOnePowerOfTen) {
  EXPECT_EQ(format_uncertain(4.808e-15, 1.6e-13, "F"), "(0.0 ± 1.6)e-13 F");
  EXPECT_EQ(format_uncertain(-2.1018e-10, 3.3e-13, "C/N"), "(-2.1018 ± 0.0033)e-10 C/N");
  EXPECT_EQ(format_uncertain(6.66e10, 1.2e8, "Pa"), "(6.660 ± 0.012)e10 Pa");
  EXPECT_EQ(format_uncertain(1.04e6, 2.2e9, "Hz"), "(0.0 ± 2.2)e9 Hz");
  EXPECT_EQ(format_uncertain(-0.000214, 0.00003), "(-2.14 ± 0.30)e-4");
  EXPECT_EQ(format_uncertain(0.538490, 0.000072), "0.538490 ± 0.000072");  // six decimals still plain
  EXPECT_EQ(format_uncertain(0.5384901, 0.0000072), "(5.384901 ± 0.000072)e-1");
  // σ below the value's resolution: the value in full, σ as it is.
  EXPECT_EQ(format_uncertain(1.0, 1e-300), "1 ± 1e-300");
}

TEST(UncertainText, SiPrefixesForSiUnits) {
  EXPECT_EQ(format_si(14846e-12, 73.845e-12, "F"), "14.846 ± 0.074 nF");
  EXPECT_EQ(format_si(4.808e-15, 1.6e-13, "F"), "0 ± 160 fF");
  EXPECT_EQ(format_si(33.32, 0.79, "ohm"), "33.32 ± 0.79 ohm");
  EXPECT_EQ(format_si(1.0e-7, 2.3e-9, "s"), "100.0 ± 2.3 ns");
  EXPECT_EQ(format_si(50350, 34, "Hz"), "50.350 ± 0.034 kHz");
  EXPECT_EQ(format_si(6.66e10, 1.2e8, "Pa"), "(6.660 ± 0.012)e10 Pa");  // not an SI-prefixed unit here
  EXPECT_EQ(format_si(0.0, 5e275, "F"), "(0.0 ± 5.0)e275 F");           // beyond the prefixes: none
}

TEST(UncertainText, NeverInfOrNanAsASigma) {
  for (double s : {kInf, -kInf, kNaN, -1.0}) {
    const std::string t = format_uncertain(50350, s, "Hz");
    EXPECT_EQ(t, "50350 Hz (σ not identifiable)") << s;
    EXPECT_EQ(format_uncertain(50350, s, "Hz", {true}), "50350 ± — Hz") << s;
    for (const char* bad : {"inf", "nan"}) EXPECT_EQ(t.find(bad), std::string::npos) << t;
  }
  EXPECT_EQ(format_si(4.8e-15, kInf, "F"), "4.8 fF (σ not identifiable)");
  // A value that is not finite is "—", whatever σ.
  EXPECT_EQ(format_uncertain(kNaN, 3), "—");
  EXPECT_EQ(format_uncertain(kInf, kInf, "Hz"), "—");
  EXPECT_EQ(format_value(kNaN, "Hz"), "—");
}

TEST(UncertainText, ZeroSigmaIsExact) {
  EXPECT_EQ(format_uncertain(2.5, 0), "2.5 ± 0 (exact)");
  EXPECT_EQ(format_uncertain(3140, 0, "ohm", {true}), "3140 ± 0 ohm");
}

TEST(UncertainText, ProbabilitiesBelowWhatADoubleHoldsHaveAFloor) {
  EXPECT_EQ(format_probability_log10(-8221599), "< 1e-300");
  EXPECT_EQ(format_probability_log10(-301), "< 1e-300");
  EXPECT_EQ(format_probability_log10(-12), "1e-12");
  EXPECT_EQ(format_probability_log10(std::log10(0.27)), "0.27");
  EXPECT_EQ(format_probability_log10(0.0), "1");
  EXPECT_EQ(format_probability_log10(kNaN), "—");
}

TEST(UserMessage, InternalFunctionNamesAreRemoved) {
  EXPECT_EQ(user_message("find_preset: unknown material 'x' (known: apc850, pzt4)"),
            "unknown material 'x' (known: apc850, pzt4)");
  EXPECT_EQ(user_message("fig.txt: read_impedance_table: line 3: expected 2 numbers"),
            "fig.txt: line 3: expected 2 numbers");
  EXPECT_EQ(user_message("prony_ss: select_order: the Hankel matrix is zero"), "the Hankel matrix is zero");
  EXPECT_EQ(user_message("the estimate failed (impedance_fft: fewer than 2 bins in [fmin, fmax])"),
            "the estimate failed (fewer than 2 bins in [fmin, fmax])");
  EXPECT_EQ(user_message("shot 3/8 failed: redpitaya::Digitizer::configure: rate 3e9 not supported"),
            "shot 3/8 failed: rate 3e9 not supported");
  EXPECT_EQ(user_message("comedi::Driver::configure: no range holds 60 V"), "no range holds 60 V");
}

TEST(UserMessage, WhatTheUserWroteStays) {
  // Limits quantities, effect names, file names and addresses are not function names.
  for (const char* m : {"limits.toml:12: tan_delta: min 1 > max 0", "series_resistance: 900 ohm is out of bounds",
                        "run_1: no such file or folder", "tcp://127.0.0.1:5999: cannot connect: Connection refused",
                        "--shard '3/2': I must be in 0..1"})
    EXPECT_EQ(user_message(m), m);
}

// Every snake_case name a library puts before ": " in a message is in
// internal_function_names(): a new one must be added there (or its prefix
// dropped), else the CLI would print it.
TEST(UserMessage, TheListKnowsEveryPrefixInTheSources) {
  namespace fs = std::filesystem;
  const auto& names = piezo::jobs::internal_function_names();
  const std::set<std::string_view> known(names.begin(), names.end());
  const std::regex literal(R"re("([a-z][a-z0-9]*(?:_[a-z0-9]+)+): )re");
  const std::regex who(R"re(\b(?:who|fn)\s*=\s*"([a-z][a-z0-9]*(?:_[a-z0-9]+)+)")re");
  std::size_t files = 0;
  for (const char* dir : {"acquisition", "drivers", "dsp", "model", "update", "jobs"}) {
    for (const auto& e : fs::recursive_directory_iterator(fs::path(PIEZO_SOURCE_DIR) / dir)) {
      const auto ext = e.path().extension();
      if (ext != ".cpp" && ext != ".hpp") continue;
      ++files;
      std::ifstream in(e.path());
      std::string line;
      for (int n = 1; std::getline(in, line); ++n) {
        const auto first = line.find_first_not_of(" \t");
        if (first != std::string::npos && line.compare(first, 2, "//") == 0) continue;  // a comment
        if (line.find(": ") == std::string::npos && line.find("who") == std::string::npos &&
            line.find("fn") == std::string::npos)
          continue;  // nothing to match (std::regex is slow)
        for (const std::regex* re : {&literal, &who})
          for (std::sregex_iterator it(line.begin(), line.end(), *re), end; it != end; ++it)
            EXPECT_TRUE(known.count((*it)[1].str()))
                << e.path().string() << ":" << n << ": \"" << (*it)[1].str()
                << ": \" is not in jobs::internal_function_names(): add it there, or drop the prefix";
      }
    }
  }
  EXPECT_GT(files, 100u);  // the sources were found
}
