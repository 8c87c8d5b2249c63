#pragma once
// IEEE 488.2 definite-length arbitrary block data: "#" <n> <n digits: length> <bytes>.
// Used for waveforms in both directions (AWG upload, DAQ fetch).
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace piezo::drivers {

// "#<n><len>" header for a payload of `len` bytes.
std::string block_header(std::size_t len);

// Header + payload.
std::vector<std::uint8_t> encode_block(std::span<const std::uint8_t> payload);

struct BlockHeader {
  std::size_t header_len = 0;  // bytes of "#n<len>"
  std::size_t payload_len = 0;
};

// Parses a header at the start of `data`. Returns nullopt if more bytes are
// needed; throws std::invalid_argument on a malformed header (no '#', a
// non-digit, an indefinite "#0" block where a definite one is required).
std::optional<BlockHeader> parse_block_header(std::span<const std::uint8_t> data);

}  // namespace piezo::drivers
