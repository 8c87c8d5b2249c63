#include "dsp/impedance_files/text.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <stdexcept>

namespace piezo::dsp::zfiles {

std::string slurp(std::istream& in, const char* fn, const std::string& name) {
  constexpr std::size_t kMax = std::size_t{256} << 20;
  std::string text;
  char buf[65536];
  while (in.read(buf, sizeof buf) || in.gcount() > 0) {
    text.append(buf, static_cast<std::size_t>(in.gcount()));
    if (text.size() > kMax) fail(fn, name, 0, "larger than 256 MB: not an impedance sweep");
  }
  return text;
}

std::vector<TextLine> split_lines(std::string_view text) {
  if (text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);
  std::vector<TextLine> lines;
  int number = 0;
  std::size_t start = 0;
  for (std::size_t i = 0; i <= text.size(); ++i) {
    if (i < text.size() && text[i] != '\n' && text[i] != '\r') continue;
    if (i == text.size() && start == i) break;  // no empty line after the final break
    lines.push_back({++number, std::string(text.substr(start, i - start))});
    if (i + 1 < text.size() && text[i] == '\r' && text[i + 1] == '\n') ++i;
    start = i + 1;
  }
  return lines;
}

std::string_view trim(std::string_view s) {
  const auto blank = [](char c) { return c == ' ' || c == '\t' || c == '\v' || c == '\f'; };
  while (!s.empty() && blank(s.front())) s.remove_prefix(1);
  while (!s.empty() && blank(s.back())) s.remove_suffix(1);
  return s;
}

std::string lower(std::string_view s) {
  std::string out(s);
  for (auto& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

bool istarts_with(std::string_view s, std::string_view prefix) {
  return s.size() >= prefix.size() && iequals(s.substr(0, prefix.size()), prefix);
}

bool iequals(std::string_view a, std::string_view b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::tolower(static_cast<unsigned char>(x)) ==
                  std::tolower(static_cast<unsigned char>(y));
         });
}

bool parse_number(std::string_view s, double& out, bool decimal_comma) {
  s = trim(s);
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  if (s.empty() || s.front() == '+' || s.size() > 64) return false;
  char buf[65];
  std::size_t n = 0;
  bool comma_seen = false;
  for (char c : s) {
    if (c == ',') {
      if (!decimal_comma || comma_seen) return false;
      comma_seen = true;
      c = '.';
    }
    buf[n++] = c;
  }
  const auto r = std::from_chars(buf, buf + n, out, std::chars_format::general);
  return r.ec == std::errc() && r.ptr == buf + n;
}

std::vector<std::string> split_fields(std::string_view line, char sep) {
  std::vector<std::string> fields;
  std::string cur;
  bool quoted = false, in_field = false;
  const auto is_sep = [&](char c) { return sep == ' ' ? (c == ' ' || c == '\t') : c == sep; };
  const auto flush = [&] {
    fields.emplace_back(trim(cur));
    cur.clear();
    in_field = false;
  };
  for (char c : line) {
    if (c == '"') {
      quoted = !quoted;
      in_field = true;
      continue;
    }
    if (!quoted && is_sep(c)) {
      if (sep == ' ') {
        if (in_field) flush();
      } else {
        flush();
      }
      continue;
    }
    cur += c;
    in_field = true;
  }
  if (sep == ' ') {
    if (in_field) flush();
  } else {
    flush();
  }
  return fields;
}

std::string printable(std::string_view s) {
  std::string out;
  out.reserve(s.size());
  for (std::size_t i = 0; i < s.size();) {
    const auto c = static_cast<unsigned char>(s[i]);
    std::size_t n = c < 0x80 ? 1 : (c >> 5) == 0x6 ? 2 : (c >> 4) == 0xE ? 3 : (c >> 3) == 0x1E ? 4 : 0;
    bool ok = n > 0 && i + n <= s.size() && !(n == 2 && c < 0xC2) && !(n == 4 && c > 0xF4);
    for (std::size_t k = 1; ok && k < n; ++k)
      ok = (static_cast<unsigned char>(s[i + k]) & 0xC0) == 0x80;
    if (ok && n == 3) {  // no overlong forms or surrogates
      const auto d = static_cast<unsigned char>(s[i + 1]);
      ok = !(c == 0xE0 && d < 0xA0) && !(c == 0xED && d >= 0xA0);
    }
    if (ok && n == 4) {
      const auto d = static_cast<unsigned char>(s[i + 1]);
      ok = !(c == 0xF0 && d < 0x90) && !(c == 0xF4 && d >= 0x90);
    }
    if (!ok) {
      out += '?';
      ++i;
      continue;
    }
    out.append(s.substr(i, n));
    i += n;
  }
  return out;
}

std::string list(const std::vector<std::string>& items) {
  std::string s = "[";
  for (std::size_t i = 0; i < items.size(); ++i) s += (i ? ", " : "") + items[i];
  return s + "]";
}

void fail(const char* /*fn*/, const std::string& name, int line, const std::string& what) {
  // The reader's function name stays out: the user sees the file, the line and what is wrong.
  std::string msg = name + ": ";
  if (line > 0) msg += "line " + std::to_string(line) + ": ";
  throw std::invalid_argument(printable(msg + what));
}

ImportedImpedance CurveBuilder::finish() {
  auto& c = out;
  std::size_t n = c.f_hz.size();
  if (n == 0) fail(fn_, name_, 0, "no data rows");
  if (!c.abs_sigma_ohm.empty() && c.abs_sigma_ohm.size() != n)
    fail(fn_, name_, 0, "uncertainty columns and data rows differ in number");
  for (std::size_t i = 0; i < n; ++i) {
    const auto z = c.z_ohm[i];
    if (!(c.f_hz[i] >= 0) || !std::isfinite(c.f_hz[i]))
      fail(fn_, name_, line_[i],
           "frequency " + std::to_string(c.f_hz[i]) + " Hz is not finite and >= 0");
    if (!std::isfinite(z.real()) || !std::isfinite(z.imag()) || !std::isfinite(std::abs(z)))
      fail(fn_, name_, line_[i],
           "impedance is not finite (the value gives Z = " + std::to_string(z.real()) + " + j" +
               std::to_string(z.imag()) + " ohm)");
    if (!c.abs_sigma_ohm.empty() &&
        (!(c.abs_sigma_ohm[i] >= 0) || !std::isfinite(c.abs_sigma_ohm[i]) ||
         !(c.phase_sigma_rad[i] >= 0) || !std::isfinite(c.phase_sigma_rad[i])))
      fail(fn_, name_, line_[i], "uncertainty is not finite and >= 0");
  }
  bool ascending = true, descending = n > 1, ties = false;
  for (std::size_t i = 1; i < n; ++i) {
    ascending = ascending && c.f_hz[i] > c.f_hz[i - 1];
    descending = descending && c.f_hz[i] < c.f_hz[i - 1];
    ties = ties || c.f_hz[i] == c.f_hz[i - 1];
  }
  // A sweep that repeats a frequency (a low-frequency log sweep printed with a
  // coarse frequency resolution, LabOne's MFIA export) and is otherwise
  // ascending: each run of equal frequencies becomes one point, Z averaged.
  bool nondecreasing = ties && c.abs_sigma_ohm.empty();
  for (std::size_t i = 1; i < n && nondecreasing; ++i)
    nondecreasing = c.f_hz[i] >= c.f_hz[i - 1];
  if (nondecreasing) {
    std::size_t w = 0, merged = 0;
    for (std::size_t i = 0; i < n;) {
      std::size_t j = i;
      std::complex<double> sum = 0;
      while (j < n && c.f_hz[j] == c.f_hz[i]) sum += c.z_ohm[j++];
      merged += j - i - 1;
      c.f_hz[w] = c.f_hz[i];
      c.z_ohm[w] = sum / static_cast<double>(j - i);
      line_[w] = line_[i];
      ++w;
      i = j;
    }
    c.f_hz.resize(w);
    c.z_ohm.resize(w);
    line_.resize(w);
    n = w;
    c.notes.push_back(std::to_string(merged) +
                      " point(s) repeat the frequency of the point before: each run of equal "
                      "frequencies averaged into one point (" +
                      std::to_string(w) + " points left)");
    ascending = true;
  }
  if (!ascending && descending) {
    std::reverse(c.f_hz.begin(), c.f_hz.end());
    std::reverse(c.z_ohm.begin(), c.z_ohm.end());
    std::reverse(c.abs_sigma_ohm.begin(), c.abs_sigma_ohm.end());
    std::reverse(c.phase_sigma_rad.begin(), c.phase_sigma_rad.end());
    c.notes.push_back("descending sweep: reversed to ascending frequency");
  } else if (!ascending) {
    for (std::size_t i = 1; i < n; ++i)
      if (!(c.f_hz[i] > c.f_hz[i - 1]))
        fail(fn_, name_, line_[i],
             "frequencies must be strictly ascending (" + std::to_string(c.f_hz[i]) + " Hz after " +
                 std::to_string(c.f_hz[i - 1]) + " Hz on line " + std::to_string(line_[i - 1]) +
                 ")");
  }
  std::size_t active = 0;
  for (const auto& z : c.z_ohm)
    if (z.real() < -1e-9 * std::abs(z)) ++active;
  if (active > 0)
    c.notes.push_back("Re Z < 0 (phase beyond ±90°) on " + std::to_string(active) + " of " +
                      std::to_string(n) +
                      " points: not a passive impedance as written (a phase offset or inverted "
                      "leads?); read as it is");
  for (auto& note : c.notes) note = printable(note);
  c.format_name = printable(c.format_name);
  c.quantity = printable(c.quantity);
  return std::move(c);
}

}  // namespace piezo::dsp::zfiles
