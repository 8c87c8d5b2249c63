#include "dsp/impedance_files/touchstone.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <optional>
#include <sstream>

#include "dsp/impedance_files/quantities.hpp"

namespace piezo::dsp {

namespace zfiles {

namespace {

constexpr const char* kFn = "read_touchstone";

std::vector<std::string> words(std::string_view s) {
  std::vector<std::string> w;
  std::istringstream ss{std::string(s)};
  std::string t;
  while (ss >> t) w.push_back(t);
  return w;
}

// 2 for a ".s2p" file name, 1 for ".s1p", 0 otherwise.
int ports_of_name(const std::string& name) {
  const auto dot = name.rfind('.');
  if (dot == std::string::npos) return 0;
  const std::string ext = lower(std::string_view(name).substr(dot + 1));
  return ext == "s2p" ? 2 : ext == "s1p" ? 1 : 0;
}

// The median of |x| over the points.
double median_abs(std::vector<std::complex<double>> x) {
  std::vector<double> m;
  for (const auto& v : x) m.push_back(std::abs(v));
  if (m.empty()) return 0;
  std::nth_element(m.begin(), m.begin() + static_cast<std::ptrdiff_t>(m.size() / 2), m.end());
  return m[m.size() / 2];
}

std::string fmt(double v) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.10g", v);
  return buf;
}

}  // namespace

bool touchstone_option_line(std::string_view line) {
  line = trim(line);
  if (line.empty() || line.front() != '#') return false;
  line.remove_prefix(1);
  if (const auto bang = line.find('!'); bang != std::string_view::npos) line = line.substr(0, bang);
  const auto w = words(line);
  for (std::size_t i = 0; i < w.size(); ++i) {
    const std::string t = lower(w[i]);
    if (t == "hz" || t == "khz" || t == "mhz" || t == "ghz" || t == "s" || t == "y" || t == "z" ||
        t == "g" || t == "h" || t == "ri" || t == "ma" || t == "db")
      continue;
    double v;
    if (t == "r" && i + 1 < w.size() && parse_number(w[i + 1], v)) {
      ++i;
      continue;
    }
    return false;
  }
  return true;
}

ImportedImpedance read_touchstone(const std::vector<TextLine>& lines, const std::string& name) {
  const char* fn = kFn;
  double unit = 1e9, r = 50.0;
  char param = 's';
  std::string form = "ma";
  bool option_seen = false, version2 = false, network_data = false, ended = false, in_info = false,
       reference_pending = false, data_started = false;
  std::optional<double> reference;
  long long expected = -1;
  CurveBuilder b(fn, name);
  std::vector<double> pending;  // values of the point being read (v2.0: may span lines)
  int pending_line = 0;
  std::vector<std::pair<int, std::array<double, 9>>> points;
  const int named_ports = ports_of_name(name);
  int ports = named_ports == 2 ? 2 : 1;
  bool order_21_first = true;  // 1.x two-port lines: S11 S21 S12 S22

  for (const auto& L : lines) {
    std::string_view t = L.text;
    if (const auto bang = t.find('!'); bang != std::string_view::npos) t = t.substr(0, bang);
    t = trim(t);
    if (t.empty()) continue;
    if (ended) fail(fn, name, L.number, "content after [End]");
    if (in_info) {
      if (istarts_with(t, "[End Information]")) in_info = false;
      continue;
    }
    if (reference_pending && t.front() != '[') {
      double v;
      const auto w = words(t);
      if (w.empty() || w.size() > 2 || !parse_number(w[0], v) || !(v > 0) || !std::isfinite(v))
        fail(fn, name, L.number, "[Reference] needs one positive resistance per port");
      reference = v;
      reference_pending = false;
      continue;
    }
    if (t.front() == '[') {
      const auto close = t.find(']');
      if (close == std::string_view::npos) fail(fn, name, L.number, "keyword without ']'");
      const std::string key = lower(t.substr(1, close - 1));
      const auto args = words(t.substr(close + 1));
      const auto one_int = [&](long long& out) {
        double v;
        if (args.size() != 1 || !parse_number(args[0], v) || v != std::floor(v) || !(v >= 0) ||
            v > 1e12)
          fail(fn, name, L.number, "[" + key + "] needs one whole number");
        out = static_cast<long long>(v);
      };
      if (key == "version") {
        if (option_seen || data_started) fail(fn, name, L.number, "[Version] must come first");
        if (args.size() != 1 || (args[0] != "2.0" && args[0] != "2.1"))
          fail(fn, name, L.number,
               "[Version] " + (args.empty() ? std::string() : args[0]) +
                   ": only 2.0 and 2.1 are known");
        version2 = true;
      } else if (key == "number of ports") {
        long long n;
        one_int(n);
        if (n != 1 && n != 2)
          fail(fn, name, L.number,
               "[Number of Ports] " + std::to_string(n) +
                   ": only one-port (.s1p) and two-port (.s2p) files are read");
        ports = static_cast<int>(n);
      } else if (key == "number of frequencies") {
        one_int(expected);
        if (expected < 1) fail(fn, name, L.number, "[Number of Frequencies] must be positive");
      } else if (key == "reference") {
        if (args.empty()) {
          reference_pending = true;
        } else {
          double v;
          if (args.size() > 2 || !parse_number(args[0], v) || !(v > 0) || !std::isfinite(v))
            fail(fn, name, L.number, "[Reference] needs one positive resistance per port");
          reference = v;
        }
      } else if (key == "network data") {
        network_data = true;
      } else if (key == "end") {
        ended = true;
      } else if (key == "begin information") {
        in_info = true;
      } else if (key == "mixed-mode order") {
        fail(fn, name, L.number, "mixed-mode data is not read (one single-ended port only)");
      } else if (key == "number of noise frequencies" || key == "noise data") {
        fail(fn, name, L.number, "noise data belongs to two-port files");
      } else if (key == "two-port data order") {
        order_21_first = args.empty() || args[0] != "12_21";
      } else if (key == "matrix format") {
        if (!args.empty() && lower(args[0]) != "full")
          fail(fn, name, L.number, "[Matrix Format] " + args[0] + ": only Full is read");
      } else {
        b.out.notes.push_back("keyword [" + std::string(t.substr(1, close - 1)) + "] on line " +
                              std::to_string(L.number) + " ignored");
      }
      continue;
    }
    if (t.front() == '#') {
      if (option_seen) {
        b.out.notes.push_back("option line " + std::to_string(L.number) +
                              " ignored (only the first counts)");
        continue;
      }
      if (data_started) fail(fn, name, L.number, "option line after the data");
      option_seen = true;
      const auto w = words(t.substr(1));
      for (std::size_t i = 0; i < w.size(); ++i) {
        const std::string k = lower(w[i]);
        if (k == "hz")
          unit = 1;
        else if (k == "khz")
          unit = 1e3;
        else if (k == "mhz")
          unit = 1e6;
        else if (k == "ghz")
          unit = 1e9;
        else if (k == "s" || k == "z" || k == "y")
          param = k[0];
        else if (k == "g" || k == "h")
          fail(fn, name, L.number,
               "parameter " + w[i] + ": G and H parameters belong to two-port files");
        else if (k == "ri" || k == "ma" || k == "db")
          form = k;
        else if (k == "r") {
          if (i + 1 >= w.size() || !parse_number(w[i + 1], r) || !(r > 0) || !std::isfinite(r))
            fail(fn, name, L.number, "R needs a positive reference resistance");
          ++i;
        } else {
          fail(fn, name, L.number, "unknown option '" + w[i] + "'");
        }
      }
      continue;
    }
    // Network data.
    if (version2 && !network_data) fail(fn, name, L.number, "data before [Network Data]");
    const bool first_data = !data_started;
    data_started = true;
    const auto w = words(t);
    // A 1.x file of 9 values a line, not named .s1p: two ports.
    if (!version2 && first_data && w.size() == 9 && named_ports != 1)
      ports = 2;
    const std::size_t per = ports == 2 ? 9 : 3;
    if (!version2 && w.size() != per)
      fail(fn, name, L.number,
           std::to_string(w.size()) + " values: a " + (ports == 2 ? "two" : "one") +
               "-port line is " + (ports == 2 ? "'f S11 S21 S12 S22' (8 values after f)" : "'f a b'") +
               (w.size() > per ? " (a file of more ports?)" : ""));
    for (const auto& s : w) {
      double v;
      if (!parse_number(s, v)) fail(fn, name, L.number, "'" + s + "' is not a number");
      if (pending.empty()) pending_line = L.number;
      pending.push_back(v);
      if (pending.size() == per) {
        std::array<double, 9> p{};
        std::copy(pending.begin(), pending.end(), p.begin());
        points.push_back({pending_line, p});
        pending.clear();
      }
    }
  }
  if (reference_pending) fail(fn, name, 0, "[Reference] without a value");
  if (!pending.empty())
    fail(fn, name, pending_line,
         std::to_string(pending.size()) + " value(s) left over: a " +
             (ports == 2 ? "two-port point is 'f' and 8 values" : "one-port point is 'f a b'"));
  if (version2 && !network_data) fail(fn, name, 0, "no [Network Data]");
  if (version2 && !ended) b.out.notes.push_back("no [End] keyword");
  if (expected >= 0 && static_cast<long long>(points.size()) != expected)
    fail(fn, name, 0,
         "[Number of Frequencies] is " + std::to_string(expected) + " but the file has " +
             std::to_string(points.size()) + " points");
  if (!option_seen) b.out.notes.push_back("no option line: Touchstone defaults GHz S MA R 50");

  const double z0 = reference && param == 's' ? *reference : r;
  if (reference && param != 's')
    b.out.notes.push_back("[Reference] applies to S-parameters only: ignored for " +
                          std::string(1, static_cast<char>(std::toupper(param))));
  const PairSpec xs{Quantity::Z,
                    form == "ri"   ? Part::Re
                    : form == "ma" ? Part::Mag
                                   : Part::MagDb,
                    form == "ri" ? Part::Im : Part::Phase, 50.0};
  const auto value = [&](const std::array<double, 9>& p, std::size_t k) {
    const double second = form == "ri" ? p[k + 1] : p[k + 1] * std::numbers::pi / 180.0;
    return to_impedance(xs, p[0] * unit, p[k], second);  // the value as written
  };
  bool through = false;
  if (ports == 2) {
    if (param != 's')
      fail(fn, name, 0,
           std::string("two-port ") + static_cast<char>(std::toupper(param)) +
               "-parameters are not read (S-parameters of a two-port are: S21 as a device in "
               "series between the ports)");
    const std::size_t k21 = order_21_first ? 3 : 5;
    std::vector<std::complex<double>> s21;
    for (const auto& pt : points) s21.push_back(value(pt.second, k21));
    const double m = median_abs(s21);
    // A bare series element has S11 + S21 = 1 exactly (S11 = Z/(Z + 2 z0)).
    std::vector<std::complex<double>> series_misfit;
    for (std::size_t i = 0; i < points.size(); ++i)
      series_misfit.push_back(value(points[i].second, 1) + s21[i] - 1.0);
    const double sm = median_abs(series_misfit);
    through = m >= 1e-3 && sm <= 0.1;
    if (through)
      b.out.notes.push_back(
          "two-port file: read as a device in series between the ports (series-through "
          "fixture), Z = 2*z0*(1 - S21)/S21 from S21 (median |S11 + S21 - 1| " + fmt(sm) +
          ", 0 for a bare series element); S11, S12, S22 not used; never read as a reflection");
    else if (m < 1e-3)
      b.out.notes.push_back("two-port file whose S21 is at noise level (median |S21| " +
                            fmt(20 * std::log10(std::max(m, 1e-300))) +
                            " dB): nothing passes between the ports, so the device is taken to "
                            "be on port 1 and S11 is read as a reflection");
    else
      b.out.notes.push_back(
          "two-port file that is not one element in series between the ports (median |S11 + "
          "S21 - 1| " + fmt(sm) + ", 0 for a series element: a filter, or a fixture with shunt "
          "paths), so 2*z0*(1 - S21)/S21 would not be the device's impedance: S11 read as the "
          "input impedance of port 1 with port 2 terminated in z0");
    for (std::size_t i = 0; i < points.size(); ++i) {
      const double f = points[i].second[0] * unit;
      const auto x = through ? s21[i] : value(points[i].second, 1);
      b.add(points[i].first, f, through ? 2.0 * z0 * (1.0 - x) / x : z0 * (1.0 + x) / (1.0 - x));
    }
  }
  for (const auto& [line, p] : points) {
    if (ports == 2) break;
    const double f = p[0] * unit;
    const std::complex<double> x = value(p, 1);
    std::complex<double> z;
    if (param == 's')
      z = z0 * (1.0 + x) / (1.0 - x);
    else if (param == 'z')
      z = version2 ? x : x * r;
    else
      z = 1.0 / (version2 ? x : x / r);
    b.add(line, f, z);
  }
  b.out.format = ImpedanceFileFormat::Touchstone;
  b.out.format_name = version2 ? "Touchstone 2.0" : "Touchstone 1.x";
  std::string up = form;
  for (auto& c : up) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  if (ports == 2)
    b.out.quantity = (through ? "S21 (" + up + "), series-through" : "S11 (" + up + ")") +
                     ", z0 = " + fmt(z0) + " ohm";
  else if (param == 's')
    b.out.quantity = "S11 (" + up + "), z0 = " + fmt(z0) + " ohm";
  else
    b.out.quantity = std::string(param == 'z' ? "Z (" : "Y (") + up + ")" +
                     (version2 ? " in ohm / siemens" : ", normalized to R = " + fmt(r) + " ohm");
  return b.finish();
}

}  // namespace zfiles

ImportedImpedance read_touchstone(std::istream& in, const std::string& name) {
  return zfiles::read_touchstone(zfiles::split_lines(zfiles::slurp(in, zfiles::kFn, name)), name);
}

}  // namespace piezo::dsp
