#include "drivers/ieee488_block.hpp"

#include <cstdio>
#include <stdexcept>

namespace piezo::drivers {

std::string block_header(std::size_t len) {
  char digits[24];
  int n = std::snprintf(digits, sizeof digits, "%zu", len);
  if (n > 9) throw std::invalid_argument("block_header: payload too large");
  char out[32];
  std::snprintf(out, sizeof out, "#%d%s", n, digits);
  return out;
}

std::vector<std::uint8_t> encode_block(std::span<const std::uint8_t> payload) {
  std::string h = block_header(payload.size());
  std::vector<std::uint8_t> out(h.begin(), h.end());
  out.insert(out.end(), payload.begin(), payload.end());
  return out;
}

std::optional<BlockHeader> parse_block_header(std::span<const std::uint8_t> d) {
  if (d.empty()) return std::nullopt;
  if (d[0] != '#') throw std::invalid_argument("binary block: expected '#', got byte " +
                                               std::to_string(static_cast<int>(d[0])));
  if (d.size() < 2) return std::nullopt;
  if (d[1] < '0' || d[1] > '9')
    throw std::invalid_argument("binary block: length-of-length is not a digit");
  std::size_t n = d[1] - '0';
  if (n == 0) throw std::invalid_argument("binary block: indefinite-length block (#0) not supported");
  if (d.size() < 2 + n) return std::nullopt;
  std::size_t len = 0;
  for (std::size_t i = 0; i < n; ++i) {
    std::uint8_t c = d[2 + i];
    if (c < '0' || c > '9') throw std::invalid_argument("binary block: length field has a non-digit");
    len = len * 10 + (c - '0');
  }
  return BlockHeader{2 + n, len};
}

}  // namespace piezo::drivers
