#include "drivers/idn.hpp"

#include <algorithm>
#include <cctype>

namespace piezo::drivers {

namespace {
std::string_view trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}
}  // namespace

std::optional<IdnFields> split_idn(std::string_view idn) {
  const auto c1 = idn.find(',');
  if (c1 == std::string_view::npos) return std::nullopt;
  const auto c2 = idn.find(',', c1 + 1);
  return IdnFields{
      trim(idn.substr(0, c1)),
      trim(idn.substr(c1 + 1, c2 == std::string_view::npos ? std::string_view::npos : c2 - c1 - 1))};
}

bool iequals(std::string_view a, std::string_view b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::toupper(static_cast<unsigned char>(x)) ==
                  std::toupper(static_cast<unsigned char>(y));
         });
}

}  // namespace piezo::drivers
