#include "update/features.hpp"

#include <charconv>
#include <cmath>
#include <stdexcept>
#include <string>

namespace piezo::update {

namespace {

void check_list(const std::vector<double>& v, const std::vector<double>& sigma, const char* what) {
  const std::string fn = "MeasuredFeatures::validate: ";
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (!(v[i] > 0) || !std::isfinite(v[i]))
      throw std::invalid_argument(fn + what + " must be positive and finite");
    if (i > 0 && !(v[i] > v[i - 1]))
      throw std::invalid_argument(fn + what + " must be strictly ascending");
  }
  if (!sigma.empty() && sigma.size() != v.size())
    throw std::invalid_argument(fn + what + ": sigma list has a different length");
  for (double s : sigma)
    if (!(s > 0)) throw std::invalid_argument(fn + what + ": sigmas must be > 0");
}

double to_double(std::string_view s, const char* fn) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r'))
    s.remove_suffix(1);
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  double v = 0;
  auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (s.empty() || ec != std::errc() || p != s.data() + s.size() || !std::isfinite(v))
    throw std::invalid_argument(std::string(fn) + ": not a number: '" + std::string(s) + "'");
  return v;
}

}  // namespace

void MeasuredFeatures::validate() const {
  check_list(resonances_hz, resonance_sigma_hz, "resonances_hz");
  check_list(antiresonances_hz, antiresonance_sigma_hz, "antiresonances_hz");
  if (resonances_hz.empty() && antiresonances_hz.empty())
    throw std::invalid_argument("MeasuredFeatures::validate: no resonances or anti-resonances");
  if (!(low_z_ohm > 0) || !(low_z_hz > 0) || !std::isfinite(low_z_ohm) || !std::isfinite(low_z_hz))
    throw std::invalid_argument("MeasuredFeatures::validate: low-frequency |Z| and f must be > 0");
  if (!resonances_hz.empty() && !(low_z_hz < resonances_hz.front()))
    throw std::invalid_argument(
        "MeasuredFeatures::validate: the low-frequency point must lie below the first resonance");
  if (low_z_sigma_ohm < 0)
    throw std::invalid_argument("MeasuredFeatures::validate: low_z_sigma_ohm must be >= 0");
}

double MeasuredFeatures::low_frequency_capacitance() const {
  return 1.0 / (2.0 * M_PI * low_z_hz * low_z_ohm);
}

std::vector<double> parse_list(std::string_view text) {
  std::vector<double> v;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t comma = text.find(',', start);
    const std::size_t end = comma == std::string_view::npos ? text.size() : comma;
    v.push_back(to_double(text.substr(start, end - start), "parse_list"));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return v;
}

std::pair<double, double> parse_ohm_at_hz(std::string_view text) {
  const auto at = text.find('@');
  if (at == std::string_view::npos)
    throw std::invalid_argument("parse_ohm_at_hz: expected OHM@HZ, e.g. 26804@400");
  const double z = to_double(text.substr(0, at), "parse_ohm_at_hz");
  const double f = to_double(text.substr(at + 1), "parse_ohm_at_hz");
  if (!(z > 0) || !(f > 0)) throw std::invalid_argument("parse_ohm_at_hz: OHM and HZ must be > 0");
  return {z, f};
}

}  // namespace piezo::update
