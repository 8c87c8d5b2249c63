#include "update/impedance_file.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <stdexcept>

#include "dsp/impedance_files/read_any.hpp"
#include "dsp/impedance_files/touchstone.hpp"

namespace piezo::update {

namespace {

std::ifstream open_in(const std::string& path, const char* /*fn*/) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open the file");
  return in;
}

// Messages name the file, not the function (they are the user's).
void check_curve(const ImpedanceCurve& c, const std::string& path, const char* /*fn*/) {
  const std::string fn = path;
  if (c.f_hz.size() < 5)
    throw std::invalid_argument(path + ": fewer than 5 points");
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

// The dsp readers check what a file can hold (finite, ascending); check_curve
// adds what the features need (5 points, finite |Z|).
ImpedanceCurve from_dsp(dsp::ImportedImpedance&& d, const std::string& path, const char* fn) {
  if (d.magnitude_only)
    throw std::invalid_argument(path + ": the file gives |Z| without its phase (" + d.quantity +
                                "): the features need complex Z; `piezobench figures` fits |Z| "
                                "alone");
  ImpedanceCurve c;
  c.f_hz = std::move(d.f_hz);
  c.z_ohm = std::move(d.z_ohm);
  check_curve(c, path, fn);
  return c;
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
  return from_dsp(dsp::read_impedance_any(in, path), path, "read_impedance_csv");
}

ImpedanceCurve read_touchstone_s1p(const std::string& path) {
  auto in = open_in(path, "read_touchstone_s1p");
  return parse_touchstone_s1p(in, path);
}

ImpedanceCurve parse_touchstone_s1p(std::istream& in, const std::string& path) {
  return from_dsp(dsp::read_touchstone(in, path), path, "read_touchstone_s1p");
}

ImpedanceCurve read_impedance_file(const std::string& path) {
  auto in = open_in(path, "read_impedance_file");
  return from_dsp(dsp::read_impedance_any(in, path), path, "read_impedance_file");
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
