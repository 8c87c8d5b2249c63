#include "drivers/tektronix_awg/protocol.hpp"

#include <algorithm>
#include <cctype>
#include <cstring>

namespace piezo::drivers::tektronix_awg {

namespace {
std::string_view trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}
bool iequals(std::string_view a, std::string_view b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::toupper(static_cast<unsigned char>(x)) ==
                  std::toupper(static_cast<unsigned char>(y));
         });
}
}  // namespace

const Model* find_model(std::string_view idn) {
  const auto c1 = idn.find(',');
  if (c1 == std::string_view::npos) return nullptr;
  const auto c2 = idn.find(',', c1 + 1);
  const std::string_view maker = trim(idn.substr(0, c1));
  const std::string_view model =
      trim(idn.substr(c1 + 1, c2 == std::string_view::npos ? std::string_view::npos : c2 - c1 - 1));
  if (!iequals(maker, "TEKTRONIX")) return nullptr;
  for (const auto& m : kModels)
    if (m.idn_model == model) return &m;
  return nullptr;
}

std::vector<std::uint8_t> encode_real_points(std::span<const float> values,
                                             std::span<const std::uint8_t> markers) {
  std::vector<std::uint8_t> out(values.size() * kRealPointBytes);
  for (std::size_t i = 0; i < values.size(); ++i) {
    std::uint8_t* p = &out[kRealPointBytes * i];
    std::uint32_t bits;
    std::memcpy(&bits, &values[i], 4);
    for (int b = 0; b < 4; ++b) p[b] = static_cast<std::uint8_t>(bits >> (8 * b));  // little-endian
    p[4] = i < markers.size() ? markers[i] : 0;
  }
  return out;
}

std::optional<RealPoints> decode_real_points(std::span<const std::uint8_t> block) {
  if (block.size() % kRealPointBytes != 0) return std::nullopt;
  RealPoints r;
  const std::size_t n = block.size() / kRealPointBytes;
  r.values.resize(n);
  r.markers.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint8_t* p = &block[kRealPointBytes * i];
    std::uint32_t bits = 0;
    for (int b = 0; b < 4; ++b) bits |= static_cast<std::uint32_t>(p[b]) << (8 * b);
    std::memcpy(&r.values[i], &bits, 4);
    r.markers[i] = p[4];
  }
  return r;
}

std::vector<std::uint8_t> trigger_markers(std::size_t points) {
  std::vector<std::uint8_t> m(points, 0);
  if (points > 0) std::fill_n(m.begin(), std::max<std::size_t>(1, points / 2), kMarker1Bit);
  return m;
}

}  // namespace piezo::drivers::tektronix_awg
