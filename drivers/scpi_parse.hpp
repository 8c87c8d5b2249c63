#pragma once
// Server-side SCPI parsing, for the simulated instruments: splitting a byte
// stream into program messages (aware of IEEE 488.2 binary blocks, which may
// contain newlines), and matching headers against patterns written in the
// manuals' notation: "[SOURce#:]FUNCtion:ARBitrary:SRATe" — upper case is the
// short form, lower case the optional rest, [..] an optional node, '#' a
// numeric suffix (default 1).
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace piezo::drivers::scpi {

struct ProgramMessage {
  std::string text;  // header and parameters (up to the block, if any)
  std::vector<std::uint8_t> block;  // binary block payload, if the message had one
  bool has_block = false;
};

// Accumulates bytes and yields complete messages terminated by '\n'.
// A '#' starts a definite-length block only outside quoted strings and when a
// well-formed "#<n><len>" header follows; otherwise it is text ("#H1F" is a
// hexadecimal number in SCPI, "Ch#1" a string). Never throws: how the bytes
// were cut into feed() calls does not change the messages.
class InputFramer {
 public:
  void feed(std::span<const std::uint8_t> bytes);
  std::optional<ProgramMessage> next();

 private:
  std::vector<std::uint8_t> buf_;
  std::size_t scan_ = 0;  // bytes of buf_ already scanned for the current message
  char quote_ = 0;        // the quote open at scan_, or 0
};

struct Command {
  std::string header;  // e.g. "SOUR1:FUNC:ARB:SRAT" (as sent, without leading ':')
  bool query = false;
  std::vector<std::string> params;  // comma-separated, trimmed
};

// Splits "HDR? p1,p2" into a Command (';'-separated lists: see split_commands).
Command parse_command(const std::string& text);
std::vector<std::string> split_commands(const std::string& text);

// Header match; on success fills the numeric suffixes met at '#' nodes. A
// suffix too large for an int does not match (never throws).
bool match(const std::string& pattern, const std::string& header, std::vector<int>* suffixes = nullptr);

}  // namespace piezo::drivers::scpi
