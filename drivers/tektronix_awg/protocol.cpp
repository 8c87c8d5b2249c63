#include "drivers/tektronix_awg/protocol.hpp"

#include <algorithm>
#include <cctype>
#include <cstring>

#include "drivers/idn.hpp"

namespace piezo::drivers::tektronix_awg {

const Model* find_model(std::string_view idn) {
  const auto f = split_idn(idn);
  if (!f || !iequals(f->maker, "TEKTRONIX")) return nullptr;
  for (const auto& m : kModels)
    if (m.idn_model == f->model) return &m;
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
