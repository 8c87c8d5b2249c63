#pragma once
// A Markdown table of a doc page, for the tests that check the docs' tables
// against the registries (commands, estimators, driver families): the line
// that equals `header` and every '|' line right after it, each with its '\n'.
// Empty when the page has no such header line.
#include <fstream>
#include <sstream>
#include <string>

#ifndef PIEZO_SOURCE_DIR
#error "PIEZO_SOURCE_DIR: the tests' CMake function piezo_add_gtest defines it"
#endif

namespace piezo::test {

inline std::string doc_table(const std::string& relative_path, const std::string& header) {
  std::ifstream in(std::string(PIEZO_SOURCE_DIR) + "/" + relative_path);
  std::string line, out;
  bool inside = false;
  while (std::getline(in, line)) {
    if (!inside && line == header) inside = true;
    if (!inside) continue;
    if (line.empty() || line.front() != '|') break;
    out += line + "\n";
  }
  return out;
}

}  // namespace piezo::test
