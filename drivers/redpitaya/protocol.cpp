#include "drivers/redpitaya/protocol.hpp"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "drivers/idn.hpp"

namespace piezo::drivers::redpitaya {

bool accepts_idn(std::string_view idn) {
  const auto f = split_idn(idn);
  if (!f || !iequals(f->maker, "REDPITAYA")) return false;
  for (auto m : kIdnModels)
    if (iequals(f->model, m)) return true;
  return false;
}

std::optional<RateChoice> choose_decimation(double wanted_hz, const Board& b) {
  if (!(wanted_hz > 0) || !std::isfinite(wanted_hz)) return std::nullopt;
  std::optional<RateChoice> best;
  for (unsigned d : kDecimations) {
    const double rate = b.adc_rate_hz / d;
    if (rate >= wanted_hz * (1 - 1e-9)) best = RateChoice{d, rate};  // ascending: keeps the largest
  }
  return best;
}

const Gain* gain_for_range(double range_v) {
  if (!(range_v > 0)) return nullptr;
  for (const auto& g : kGains)
    if (range_v <= g.range_v * (1 + 1e-12)) return &g;
  return nullptr;
}

long trigger_delay_for(std::size_t pretrigger, const Board& b) {
  return static_cast<long>(b.buffer_samples / 2) - static_cast<long>(pretrigger);
}

std::string gain_command(int input, std::string_view gain) {
  return "ACQ:SOUR" + std::to_string(input) + ":GAIN " + std::string(gain);
}
std::string data_query(int input) { return "ACQ:SOUR" + std::to_string(input) + ":DATA?"; }

std::string encode_arb_list(std::span<const float> values) {
  std::string out;
  out.reserve(values.size() * 12);
  char buf[32];
  for (std::size_t i = 0; i < values.size(); ++i) {
    std::snprintf(buf, sizeof buf, "%.9g", static_cast<double>(values[i]));
    if (i) out.push_back(',');
    out += buf;
  }
  return out;
}

std::optional<std::vector<float>> decode_arb_list(std::span<const std::string> params,
                                                  std::size_t max_points) {
  if (params.empty() || params.size() > max_points) return std::nullopt;
  std::vector<float> v(params.size());
  for (std::size_t i = 0; i < params.size(); ++i) {
    const char* s = params[i].c_str();
    char* end = nullptr;
    v[i] = std::strtof(s, &end);  // nearest float to the decimal: the float that was printed
    if (end == s || *end != '\0' || !std::isfinite(v[i])) return std::nullopt;
  }
  return v;
}

std::vector<std::uint8_t> encode_float_block_payload(std::span<const float> values) {
  std::vector<std::uint8_t> out(values.size() * 4);
  for (std::size_t i = 0; i < values.size(); ++i) {
    std::uint32_t bits;
    std::memcpy(&bits, &values[i], 4);
    for (int b = 0; b < 4; ++b) out[4 * i + b] = static_cast<std::uint8_t>(bits >> (8 * (3 - b)));
  }
  return out;
}

std::optional<std::vector<float>> decode_float_block_payload(
    std::span<const std::uint8_t> payload) {
  if (payload.size() % 4 != 0) return std::nullopt;
  std::vector<float> v(payload.size() / 4);
  for (std::size_t i = 0; i < v.size(); ++i) {
    std::uint32_t bits = 0;
    for (int b = 0; b < 4; ++b) bits = (bits << 8) | payload[4 * i + b];  // big-endian
    std::memcpy(&v[i], &bits, 4);
  }
  return v;
}

}  // namespace piezo::drivers::redpitaya
