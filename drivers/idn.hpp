#pragma once
// The *IDN? reply of IEEE 488.2 (§10.14): "<maker>,<model>,<serial>,<firmware>",
// split and trimmed, and the case-insensitive comparison the drivers' model
// tables use to recognise it.
#include <optional>
#include <string_view>

namespace piezo::drivers {

struct IdnFields {
  std::string_view maker, model;  // views into the reply, surrounding blanks trimmed
};

// nullopt when the reply has no comma (not an IEEE 488.2 identification).
std::optional<IdnFields> split_idn(std::string_view idn);

bool iequals(std::string_view a, std::string_view b);

}  // namespace piezo::drivers
