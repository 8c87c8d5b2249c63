#include "dsp/impedance_files/bode100.hpp"

#include <cctype>

#include "dsp/impedance_files/table.hpp"

namespace piezo::dsp {

namespace zfiles {

namespace {
constexpr const char* kFn = "read_bode100_csv";
}

bool bode100_header(std::string_view line) {
  line = trim(line);
  if (!line.empty() && line.front() == '"') line.remove_prefix(1);
  if (!istarts_with(line, "Frequency")) return false;
  const std::string l = lower(line);
  for (auto i = l.find("trace "); i != std::string::npos; i = l.find("trace ", i + 1)) {
    std::size_t k = i + 6;
    const std::size_t digits = k;
    while (k < l.size() && std::isdigit(static_cast<unsigned char>(l[k]))) ++k;
    if (k > digits && k < l.size() && l[k] == ':') return true;
  }
  return false;
}

ImportedImpedance read_bode100_csv(const std::vector<TextLine>& lines, const std::string& name) {
  TableOptions opt;
  opt.fn = kFn;
  opt.format = ImpedanceFileFormat::Bode100;
  opt.format_name = "Bode 100 CSV";
  opt.allow_headerless = false;
  return read_table(lines, name, opt);
}

}  // namespace zfiles

ImportedImpedance read_bode100_csv(std::istream& in, const std::string& name) {
  return zfiles::read_bode100_csv(zfiles::split_lines(zfiles::slurp(in, zfiles::kFn, name)), name);
}

}  // namespace piezo::dsp
