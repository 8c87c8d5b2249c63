#pragma once
// Parameter helpers shared by the simulated instruments' SCPI handlers.
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <string>
#include <vector>

namespace piezo::drivers::sim {

// One finite number (strtod: decimal, exponent, SCPI's NR1/NR2/NR3 forms).
inline bool parse_number(const std::string& p, double* v) {
  char* end = nullptr;
  *v = std::strtod(p.c_str(), &end);
  return end != p.c_str() && std::isfinite(*v);
}

// Exactly one parameter, a finite number.
inline bool parse_one(const std::vector<std::string>& p, double* v) {
  return p.size() == 1 && parse_number(p[0], v);
}

inline std::string upper(std::string s) {
  for (auto& ch : s) ch = static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
  return s;
}

}  // namespace piezo::drivers::sim
