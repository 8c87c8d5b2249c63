#include "dsp/impedance_io.hpp"

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
