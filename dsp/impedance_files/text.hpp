#pragma once
// Shared by the readers of dsp/impedance_files/ (not part of their API): lines
// and fields of a text file, locale-independent numbers, the error message
// format, and the builder that validates a curve once it has been read.
//   error: "<file>: line <n>: <what>" (std::invalid_argument; no function names:
//   the message is the user's)
#include <complex>
#include <istream>
#include <string>
#include <string_view>
#include <vector>

#include "dsp/impedance_files/imported_impedance.hpp"

namespace piezo::dsp::zfiles {

struct TextLine {
  int number = 0;  // 1-based line number in the file
  std::string text;
};

// The whole stream. Throws std::invalid_argument past 256 MB (no analyzer
// writes that much for one sweep).
std::string slurp(std::istream& in, const char* fn, const std::string& name);
// Lines split at LF, CR LF or a lone CR; a UTF-8 byte-order mark is removed.
std::vector<TextLine> split_lines(std::string_view text);

std::string_view trim(std::string_view s);
std::string lower(std::string_view s);
bool istarts_with(std::string_view s, std::string_view prefix);  // ASCII, case-insensitive
bool iequals(std::string_view a, std::string_view b);

// A whole field as a number: optional sign (a leading '+' too, as the
// Keysight instruments write it), decimal or scientific, "inf"/"nan" accepted
// here and refused later by the curve check. With decimal_comma, one ',' is
// taken for the decimal point. Surrounding blanks are allowed.
bool parse_number(std::string_view s, double& out, bool decimal_comma = false);

// Fields of one line. sep ' ' means runs of blanks (spaces and tabs). Double
// quotes group a field and are removed; fields are trimmed.
std::vector<std::string> split_fields(std::string_view line, char sep);

// s with every byte that is not part of valid UTF-8 replaced by '?' (a file's
// Shift-JIS or Latin-1 text quoted in a message or note: JSON needs UTF-8).
std::string printable(std::string_view s);

// "[a, b, c]" for messages.
std::string list(const std::vector<std::string>& items);

[[noreturn]] void fail(const char* fn, const std::string& name, int line, const std::string& what);

// Collects the points of a curve with the line each came from, then checks it
// (finish): at least one point, finite f >= 0 and finite Z, frequencies
// strictly ascending (a strictly descending sweep is reversed, with a note; an
// ascending one that repeats a frequency has each run of equal frequencies
// averaged into one point, with a note, when it carries no σ).
class CurveBuilder {
 public:
  CurveBuilder(const char* fn, std::string name) : fn_(fn), name_(std::move(name)) {}
  void add(int line, double f_hz, std::complex<double> z_ohm) {
    line_.push_back(line);
    out.f_hz.push_back(f_hz);
    out.z_ohm.push_back(z_ohm);
  }
  void add_sigma(double abs_sigma_ohm, double phase_sigma_rad) {
    out.abs_sigma_ohm.push_back(abs_sigma_ohm);
    out.phase_sigma_rad.push_back(phase_sigma_rad);
  }
  std::size_t size() const { return out.f_hz.size(); }
  int line_of(std::size_t i) const { return line_[i]; }
  ImportedImpedance finish();

  ImportedImpedance out;  // format, quantity and notes are filled by the reader

 private:
  const char* fn_;
  std::string name_;
  std::vector<int> line_;
};

}  // namespace piezo::dsp::zfiles
