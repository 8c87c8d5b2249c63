#include "dsp/probability_text.hpp"

#include <cmath>
#include <cstdio>

namespace piezo::dsp {

std::string probability_text(double log10_p) {
  if (std::isnan(log10_p)) return "—";
  if (log10_p >= 0) return "1";
  if (log10_p < -300) return "< 1e-300";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2g", std::pow(10.0, log10_p));
  return buf;
}

}  // namespace piezo::dsp
