#pragma once
// What a replay worker process sends back to the batch over its pipe: a
// framed, length-prefixed binary encoding of one capture's outcome (the
// results-file record with its curves, and an issue to report). Native byte
// order: both ends are the same program on the same machine.
//
// Frame: [u8 kind][u64 length][payload]. Kinds:
//   'S' stage   payload "reading" | "processing", then '\0' and the SHA-256 when known
//   'O' outcome payload encode_outcome()
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "acquisition/results_file.hpp"

namespace piezo::jobs::replay {

struct WireIssue {
  std::string path, kind, message;
};

struct Outcome {
  bool skipped = false;  // finished in an earlier run: `key` only
  bool cancelled = false;  // the batch was interrupted: nothing to record
  std::string key;
  acq::ResultRecord record;  // when !skipped && !cancelled
  std::optional<WireIssue> issue;  // goes with the record (a failure, or a report not written)
  std::optional<WireIssue> report_issue;  // a failed capture's report could not be written
};

std::string encode_outcome(const Outcome& o);
// Throws std::runtime_error for a payload that is not an encoded outcome.
Outcome decode_outcome(std::string_view payload);

std::string frame(char kind, std::string_view payload);

// Splits complete frames off the front of `buf` (bytes read so far); returns
// false while the next frame is incomplete. Throws std::runtime_error for a
// length no frame can have.
bool next_frame(std::string& buf, char& kind, std::string& payload);

}  // namespace piezo::jobs::replay
