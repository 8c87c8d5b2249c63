#include "dsp/impedance_io.hpp"

#include <cmath>
#include <cstdio>
#include <ostream>
#include <stdexcept>

namespace piezo::dsp {

namespace {
void line(std::ostream& os, const char* fmt, double a, double b, double c) {
  char buf[128];
  std::snprintf(buf, sizeof buf, fmt, a, b, c);
  os << buf;
}
}  // namespace

void write_impedance_csv(std::ostream& os, const ImpedanceResult& r) {
  os << "f_hz,re_ohm,im_ohm\n";
  for (Eigen::Index k = 0; k < r.f_hz.size(); ++k)
    line(os, "%.10g,%.10g,%.10g\n", r.f_hz[k], r.z_ohm[k].real(), r.z_ohm[k].imag());
}

void write_impedance_csv(std::ostream& os, const ImpedanceResult& r, const ImpedanceBand& b) {
  if (b.size() != r.f_hz.size()) throw std::invalid_argument("write_impedance_csv: band and estimate differ in length");
  os << "f_hz,re_ohm,im_ohm,abs_ohm,abs_sigma_ohm,phase_deg,phase_sigma_deg,coverage_factor\n";
  char buf[256];
  for (Eigen::Index k = 0; k < r.f_hz.size(); ++k) {
    std::snprintf(buf, sizeof buf, "%.10g,%.10g,%.10g,%.10g,%.6g,%.8g,%.6g,%.4g\n", r.f_hz[k], r.z_ohm[k].real(),
                  r.z_ohm[k].imag(), b.abs_ohm[k], b.abs_sigma_ohm[k], b.phase_rad[k] * 180.0 / M_PI,
                  b.phase_sigma_rad[k] * 180.0 / M_PI, b.coverage_factor);
    os << buf;
  }
}

void write_touchstone_s1p(std::ostream& os, const ImpedanceResult& r, double ref) {
  if (!(ref > 0)) throw std::invalid_argument("write_touchstone_s1p: reference must be positive");
  os << "! piezobench impedance, method " << r.method << ", " << r.samples_used << " samples\n";
  os << "! Z-parameters normalised to R (Touchstone 1.1): Z_ohm = value * R\n";
  char buf[64];
  std::snprintf(buf, sizeof buf, "# HZ Z RI R %.10g\n", ref);
  os << buf;
  for (Eigen::Index k = 0; k < r.f_hz.size(); ++k)
    line(os, "%.10g %.10g %.10g\n", r.f_hz[k], r.z_ohm[k].real() / ref, r.z_ohm[k].imag() / ref);
}

}  // namespace piezo::dsp
