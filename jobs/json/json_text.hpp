#pragma once
// JSON text of our outputs. nlohmann::json refuses (throws type_error 316)
// strings that are not UTF-8; ours can hold file names, which on Linux are
// bytes, and text from captures other tools wrote. Every JSON we print or
// write goes through here: a malformed byte becomes U+FFFD, never an
// "internal error" after the work is done.
#include <nlohmann/json.hpp>
#include <ostream>
#include <string>

namespace piezo::jobs {

// indent < 0: one line.
inline std::string json_text(const nlohmann::json& j, int indent = -1) {
  return j.dump(indent, ' ', false, nlohmann::json::error_handler_t::replace);
}

// Streamed (no serialised copy of a large document), pretty-printed.
inline void write_json(std::ostream& os, const nlohmann::json& j, unsigned indent = 2) {
  nlohmann::detail::serializer<nlohmann::json> s(nlohmann::detail::output_adapter<char>(os), ' ',
                                                 nlohmann::json::error_handler_t::replace);
  s.dump(j, true, false, indent);
}

}  // namespace piezo::jobs
