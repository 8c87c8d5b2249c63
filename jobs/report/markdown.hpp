#pragma once
// Small text helpers shared by the Markdown reports (capture and batch).
#include <cstdio>
#include <string>

namespace piezo::jobs::report {

// printf-style formatting of one number.
inline std::string fmt(const char* f, double v) {
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

// Markdown table cells must not break the table.
inline std::string cell(std::string s) {
  for (std::size_t i = 0; (i = s.find('|', i)) != std::string::npos; i += 2) s.replace(i, 1, "\\|");
  for (char& c : s)
    if (c == '\n') c = ' ';
  return s;
}

}  // namespace piezo::jobs::report
