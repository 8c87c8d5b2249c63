#include "dsp/uncertain_text.hpp"

#include "dsp/probability_text.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <utility>

namespace piezo::dsp {

namespace {

const char* const kDash = "\xE2\x80\x94";  // "—"

std::string with_unit(std::string s, std::string_view unit) {
  if (!unit.empty()) s.append(" ").append(unit);
  return s;
}

std::string fixed(double x, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", std::clamp(decimals, 0, 17), x);
  std::string s = buf;
  // A value that rounds to zero prints without a sign.
  if (s[0] == '-' && s.find_first_not_of("-0.") == std::string::npos) s.erase(0, 1);
  return s;
}

std::string general(double x, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*g", std::clamp(digits, 1, 17), x);
  return buf;
}

}  // namespace

std::string format_value(double value, std::string_view unit, int digits) {
  if (!std::isfinite(value)) return kDash;
  return with_unit(general(value, digits), unit);
}

std::string format_uncertain(double value, double sigma, std::string_view unit, const UncertainStyle& style) {
  if (!std::isfinite(value)) return style.dash;
  if (!std::isfinite(sigma) || sigma < 0) {
    if (style.compact) return with_unit(general(value, style.bare_digits) + " ± " + style.dash, unit);
    return format_value(value, unit, style.bare_digits) + " (" + style.no_sigma + ")";
  }
  if (sigma == 0) return with_unit(general(value, 6) + " ± 0", unit) + (style.compact ? "" : " (exact)");
  // σ to two significant digits: its last kept digit has the weight q = 10^(e-1).
  int e = static_cast<int>(std::floor(std::log10(sigma)));
  // σ below the value's own resolution: the value in full, σ as it is.
  if (std::abs(value) > 1e15 * sigma) return with_unit(general(value, 15) + " ± " + general(sigma, 2), unit);
  double q = std::pow(10.0, e - 1);
  double s = std::round(sigma / q) * q;
  if (s >= 99.5 * q) {  // 99.6 -> 100: three digits, one place up
    ++e;
    q *= 10;
    s = std::round(sigma / q) * q;
  }
  const double v = std::round(value / q) * q;
  const int decimals = 1 - e;  // of σ's last kept digit
  const double mag = std::max(std::abs(v), s);
  const int mag_exp = static_cast<int>(std::floor(std::log10(mag)));
  if (mag_exp >= -3 && mag_exp < 6 && decimals <= 6) {
    const int d = std::max(decimals, 0);
    return with_unit(fixed(v, d) + " ± " + fixed(s, d), unit);
  }
  // One common power of ten.
  const double scale = std::pow(10.0, mag_exp);
  const int d = decimals + mag_exp;
  std::string out = "(";  // appended piecewise: GCC 12's -Wrestrict misfires on "(" + std::string
  out.append(fixed(v / scale, d)).append(" ± ").append(fixed(s / scale, d)).append(")e");
  out.append(std::to_string(mag_exp));
  return with_unit(std::move(out), unit);
}

std::string format_si(double value, double sigma, std::string_view base_unit, const UncertainStyle& style) {
  if (!std::isfinite(value)) return style.dash;
  static const char* const kSi[] = {"F", "H", "Hz", "s", "V", "A", "W", "m", "ohm", "Ω"};
  if (std::find(std::begin(kSi), std::end(kSi), base_unit) == std::end(kSi))
    return format_uncertain(value, sigma, base_unit, style);
  double mag = std::abs(value);
  if (std::isfinite(sigma) && sigma > mag) mag = sigma;
  static const char* const kPrefix[] = {"f", "p", "n", "µ", "m", "", "k", "M", "G"};
  int k = 5;  // no prefix
  if (mag > 0) k = static_cast<int>(std::floor(std::log10(mag) / 3.0)) + 5;
  if (k < 0 || k > 8) k = 5;  // beyond f..G: the unprefixed unit and a power of ten
  const double scale = std::pow(10.0, 3 * (k - 5));
  const std::string unit = std::string(kPrefix[k]) + std::string(base_unit);
  return format_uncertain(value / scale, std::isfinite(sigma) ? sigma / scale : sigma, unit, style);
}

std::string format_probability_log10(double log10_p) { return probability_text(log10_p); }

}  // namespace piezo::dsp
