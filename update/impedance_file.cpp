#include "update/impedance_file.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace piezo::update {

namespace {

std::ifstream open_in(const std::string& path, const char* fn) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(std::string(fn) + ": cannot open '" + path + "'");
  return in;
}

std::string lower(std::string s) {
  for (auto& ch : s) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  return s;
}

void check_curve(const ImpedanceCurve& c, const std::string& path, const char* fn) {
  if (c.f_hz.size() < 5)
    throw std::invalid_argument(std::string(fn) + ": fewer than 5 points in '" + path + "'");
  for (std::size_t i = 0; i < c.f_hz.size(); ++i) {
    // Finite frequency (a Touchstone unit can overflow it) and finite |Z|
    // (features work in dB of |Z|; re and im near 1.8e308 overflow it).
    if (!(c.f_hz[i] >= 0) || !std::isfinite(c.f_hz[i]) || !std::isfinite(c.z_ohm[i].real()) ||
        !std::isfinite(c.z_ohm[i].imag()) || !std::isfinite(std::abs(c.z_ohm[i])))
      throw std::invalid_argument(std::string(fn) + ": bad value on data row " +
                                  std::to_string(i + 1));
    if (i > 0 && !(c.f_hz[i] > c.f_hz[i - 1]))
      throw std::invalid_argument(std::string(fn) +
                                  ": frequencies must be strictly ascending (row " +
                                  std::to_string(i + 1) + ")");
  }
}

bool parse_numbers(const std::string& line, char sep, std::vector<double>& out) {
  out.clear();
  std::string item;
  std::stringstream ss(line);
  while (sep == ' ' ? static_cast<bool>(ss >> item)
                    : static_cast<bool>(std::getline(ss, item, sep))) {
    std::size_t used = 0;
    try {
      out.push_back(std::stod(item, &used));
    } catch (const std::exception&) {
      return false;
    }
    while (used < item.size() && std::isspace(static_cast<unsigned char>(item[used]))) ++used;
    if (used != item.size()) return false;
  }
  return true;
}

// Vertex of the parabola through (x0,y0), (x1,y1), (x2,y2) (non-uniform spacing).
std::pair<double, double> vertex(double x0, double y0, double x1, double y1, double x2, double y2) {
  const double d0 = (y1 - y0) / (x1 - x0), d1 = (y2 - y1) / (x2 - x1);
  const double a = (d1 - d0) / (x2 - x0);
  if (!(std::abs(a) > 0)) return {x1, y1};
  const double b = d0 - a * (x0 + x1);
  double xv = -b / (2 * a);
  xv = std::clamp(xv, x0, x2);
  return {xv, y0 + d0 * (xv - x0) + a * (xv - x0) * (xv - x1)};  // Newton form
}

}  // namespace

ImpedanceCurve read_impedance_csv(const std::string& path) {
  auto in = open_in(path, "read_impedance_csv");
  return parse_impedance_csv(in, path);
}

ImpedanceCurve parse_impedance_csv(std::istream& in, const std::string& path) {
  const char* fn = "read_impedance_csv";
  ImpedanceCurve c;
  std::string line;
  std::vector<double> v;
  int lineno = 0;
  bool header_seen = false;
  while (std::getline(in, line)) {
    ++lineno;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line[0] == '#') continue;
    if (!parse_numbers(line, ',', v)) {
      if (!header_seen && c.f_hz.empty()) {
        header_seen = true;  // one header line is allowed
        continue;
      }
      throw std::invalid_argument(std::string(fn) + ": line " + std::to_string(lineno) +
                                  " is not f_hz,re_ohm,im_ohm");
    }
    if (v.size() < 3)  // further columns (the uncertainty band of `impedance --csv`) are not needed here
      throw std::invalid_argument(std::string(fn) + ": line " + std::to_string(lineno) +
                                  " needs 3 columns f_hz,re_ohm,im_ohm");
    c.f_hz.push_back(v[0]);
    c.z_ohm.emplace_back(v[1], v[2]);
  }
  check_curve(c, path, fn);
  return c;
}

ImpedanceCurve read_touchstone_s1p(const std::string& path) {
  auto in = open_in(path, "read_touchstone_s1p");
  return parse_touchstone_s1p(in, path);
}

ImpedanceCurve parse_touchstone_s1p(std::istream& in, const std::string& path) {
  const char* fn = "read_touchstone_s1p";
  double unit = 1e9, z0 = 50;
  std::string param = "s", format = "ma";
  bool option_seen = false;
  ImpedanceCurve c;
  std::string line;
  std::vector<double> v;
  int lineno = 0;
  while (std::getline(in, line)) {
    ++lineno;
    if (auto bang = line.find('!'); bang != std::string::npos) line.resize(bang);
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    if (line.find_first_not_of(" \t") != std::string::npos &&
        line[line.find_first_not_of(" \t")] == '#') {
      if (option_seen) continue;  // only the first option line counts
      option_seen = true;
      std::stringstream ss(line.substr(line.find('#') + 1));
      std::string tok;
      while (ss >> tok) {
        tok = lower(tok);
        if (tok == "hz")
          unit = 1;
        else if (tok == "khz")
          unit = 1e3;
        else if (tok == "mhz")
          unit = 1e6;
        else if (tok == "ghz")
          unit = 1e9;
        else if (tok == "s" || tok == "z")
          param = tok;
        else if (tok == "ri" || tok == "ma" || tok == "db")
          format = tok;
        else if (tok == "r") {
          if (!(ss >> z0) || !(z0 > 0))
            throw std::invalid_argument(std::string(fn) + ": bad reference impedance");
        } else
          throw std::invalid_argument(std::string(fn) + ": unsupported option '" + tok +
                                      "' (one-port S or Z only)");
      }
      continue;
    }
    if (!parse_numbers(line, ' ', v) || v.size() != 3)
      throw std::invalid_argument(std::string(fn) + ": line " + std::to_string(lineno) +
                                  " is not 'f a b' of a one-port file");
    std::complex<double> x;
    if (format == "ri")
      x = {v[1], v[2]};
    else {
      const double mag = format == "ma" ? v[1] : std::pow(10.0, v[1] / 20.0);
      x = std::polar(mag, v[2] * M_PI / 180.0);
    }
    std::complex<double> z = param == "z" ? x * z0 : z0 * (1.0 + x) / (1.0 - x);
    c.f_hz.push_back(v[0] * unit);
    c.z_ohm.push_back(z);
  }
  check_curve(c, path, fn);
  return c;
}

ImpedanceCurve read_impedance_file(const std::string& path) {
  const auto dot = path.rfind('.');
  if (dot != std::string::npos && lower(path.substr(dot)) == ".s1p")
    return read_touchstone_s1p(path);
  return read_impedance_csv(path);
}

void write_impedance_csv(const std::string& path, const ImpedanceCurve& c) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("write_impedance_csv: cannot write '" + path + "'");
  out.precision(12);
  out << "f_hz,re_ohm,im_ohm\n";
  for (std::size_t i = 0; i < c.f_hz.size(); ++i)
    out << c.f_hz[i] << ',' << c.z_ohm[i].real() << ',' << c.z_ohm[i].imag() << '\n';
}

ExtractedFeatures extract_features(const ImpedanceCurve& c, const FeatureOptions& opt) {
  const char* fn = "extract_features";
  const std::size_t n = c.f_hz.size();
  if (n < 5 || c.z_ohm.size() != n)
    throw std::invalid_argument(std::string(fn) + ": too few points");
  std::vector<double> db(n);
  for (std::size_t i = 0; i < n; ++i)
    db[i] = 20.0 * std::log10(std::max(std::abs(c.z_ohm[i]), 1e-300));
  ExtractedFeatures out;
  auto& mf = out.features;
  std::size_t i = 1;
  while (i + 1 < n && static_cast<int>(mf.resonances_hz.size()) < opt.max_modes) {
    if (!(db[i] < db[i - 1] && db[i] <= db[i + 1]) || c.f_hz[i - 1] <= 0) {
      ++i;
      continue;
    }
    std::size_t k = i + 1;  // climb to the following maximum
    while (k + 1 < n && db[k + 1] >= db[k]) ++k;
    // Weak (electrically inactive) modes on the way up leave a small dip and
    // bump; step over dips shallower than the prominence threshold.
    while (k + 1 < n) {
      std::size_t m2 = k + 1;
      while (m2 + 1 < n && db[m2 + 1] <= db[m2]) ++m2;
      if (m2 + 1 >= n || db[k] - db[m2] >= opt.min_prominence_db) break;
      std::size_t k2 = m2 + 1;
      while (k2 + 1 < n && db[k2 + 1] >= db[k2]) ++k2;
      if (!(db[k2] > db[k])) break;
      k = k2;
    }
    if (k + 1 >= n) break;  // curve ends while still rising
    if (db[k] - db[i] >= opt.min_prominence_db) {
      auto [fr, zr] = vertex(c.f_hz[i - 1], db[i - 1], c.f_hz[i], db[i], c.f_hz[i + 1], db[i + 1]);
      auto [fa, za] = vertex(c.f_hz[k - 1], db[k - 1], c.f_hz[k], db[k], c.f_hz[k + 1], db[k + 1]);
      (void)zr;
      (void)za;
      mf.resonances_hz.push_back(fr);
      mf.antiresonances_hz.push_back(fa);
    }
    i = k + 1;
  }
  if (mf.resonances_hz.empty())
    throw std::invalid_argument(std::string(fn) +
                                ": no resonance/anti-resonance pair with at least " +
                                std::to_string(opt.min_prominence_db) + " dB prominence");
  const double f_max_low = opt.low_f_fraction * mf.resonances_hz.front();
  int best = -1;
  for (std::size_t j = 0; j < n && c.f_hz[j] <= f_max_low; ++j) {
    if (!(c.f_hz[j] > 0)) continue;
    const double ph = std::arg(c.z_ohm[j]) * 180.0 / M_PI;
    if (std::abs(ph + 90.0) <= opt.capacitive_phase_tol_deg) best = static_cast<int>(j);
  }
  if (best < 0)
    throw std::invalid_argument(std::string(fn) + ": no capacitive point (phase within " +
                                std::to_string(opt.capacitive_phase_tol_deg) + "° of -90°) below " +
                                std::to_string(f_max_low) + " Hz");
  mf.low_z_hz = c.f_hz[best];
  mf.low_z_ohm = std::abs(c.z_ohm[best]);
  out.low_z_phase_deg = std::arg(c.z_ohm[best]) * 180.0 / M_PI;
  return out;
}

}  // namespace piezo::update
