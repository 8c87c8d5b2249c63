#include "dsp/impedance_files/read_any.hpp"

#include <fstream>
#include <stdexcept>

#include "dsp/impedance_files/bode100.hpp"
#include "dsp/impedance_files/columns.hpp"
#include "dsp/impedance_files/e4990a.hpp"
#include "dsp/impedance_files/hioki.hpp"
#include "dsp/impedance_files/hp4294a.hpp"
#include "dsp/impedance_files/labone.hpp"
#include "dsp/impedance_files/table.hpp"
#include "dsp/impedance_files/text.hpp"
#include "dsp/impedance_files/touchstone.hpp"

namespace piezo::dsp {

namespace {

using zfiles::TextLine;

bool touchstone_extension(const std::string& name) {
  const auto dot = name.rfind('.');
  if (dot == std::string::npos) return false;
  const std::string ext = zfiles::lower(std::string_view(name).substr(dot + 1));
  return ext == "s1p" || ext == "s2p" || ext == "ts" || ext == "snp";
}

ImpedanceFileFormat detect(const std::vector<TextLine>& lines, const std::string& name) {
  // The first line that is neither blank nor a '!' comment.
  const TextLine* first = nullptr;
  for (const auto& L : lines) {
    const auto t = zfiles::trim(L.text);
    if (t.empty() || t.front() == '!') continue;
    first = &L;
    break;
  }
  if (first) {
    const auto t = zfiles::trim(first->text);
    if (zfiles::istarts_with(t, "[Version]") || zfiles::touchstone_option_line(t) ||
        (t.front() == '#' && touchstone_extension(name)))
      return ImpedanceFileFormat::Touchstone;
  }
  for (const auto& L : lines) {
    std::string t(zfiles::trim(L.text));
    if (zfiles::e4990a_begin_line(t)) return ImpedanceFileFormat::E4990a;
    std::string u;
    for (char c : t)
      if (c != '"' && c != ' ') u += c;
    if (zfiles::iequals(u, "TRACE:A")) return ImpedanceFileFormat::Hp4294a;
  }
  if (!lines.empty() && zfiles::istarts_with(zfiles::trim(lines.front().text), "4294A"))
    return ImpedanceFileFormat::Hp4294a;
  if (first && zfiles::bode100_header(first->text)) return ImpedanceFileFormat::Bode100;
  for (std::size_t i = 0; i < lines.size() && i < 400; ++i)
    if (zfiles::hioki_header(lines[i].text)) return ImpedanceFileFormat::Hioki;
  if (zfiles::labone_file(lines)) return ImpedanceFileFormat::LabOne;
  if (first && touchstone_extension(name)) {
    // Numbers only (a Touchstone file without its option line)?
    bool numbers = true;
    for (const auto& f : zfiles::split_fields(first->text, ' ')) {
      double v;
      numbers = numbers && zfiles::parse_number(f, v);
    }
    if (numbers) return ImpedanceFileFormat::Touchstone;
  }
  return ImpedanceFileFormat::Table;
}

}  // namespace

ImpedanceFileFormat detect_impedance_format(std::string_view text, const std::string& name) {
  return detect(zfiles::split_lines(text), name);
}

ImportedImpedance read_impedance_any(std::istream& in, const std::string& name,
                                     ImpedanceFileFormat hint) {
  ImpedanceReadOptions opt;
  opt.hint = hint;
  return read_impedance_any(in, name, opt);
}

namespace {

ImportedImpedance read_lines(const std::vector<TextLine>& lines, const std::string& name,
                             const ImpedanceReadOptions& opt) {
  if (!opt.columns.empty()) {
    zfiles::TableOptions t;
    t.columns = zfiles::parse_column_spec(opt.columns);
    auto out = zfiles::read_table(lines, name, t);
    out.notes.insert(out.notes.begin(), "columns as given by --columns " + opt.columns);
    return out;
  }
  const auto format = opt.hint == ImpedanceFileFormat::Auto ? detect(lines, name) : opt.hint;
  switch (format) {
    case ImpedanceFileFormat::Touchstone:
      return zfiles::read_touchstone(lines, name);
    case ImpedanceFileFormat::Hp4294a:
      return zfiles::read_hp4294a_text(lines, name);
    case ImpedanceFileFormat::E4990a:
      return zfiles::read_e4990a_csv(lines, name);
    case ImpedanceFileFormat::Bode100:
      return zfiles::read_bode100_csv(lines, name);
    case ImpedanceFileFormat::Hioki:
      return zfiles::read_hioki_csv(lines, name);
    case ImpedanceFileFormat::LabOne:
      return zfiles::read_labone(lines, name);
    case ImpedanceFileFormat::Table:
    case ImpedanceFileFormat::Auto:
      break;
  }
  return zfiles::read_table(lines, name, zfiles::TableOptions{});
}

}  // namespace

ImportedImpedance read_impedance_any(std::istream& in, const std::string& name,
                                     const ImpedanceReadOptions& opt) {
  auto out = read_lines(zfiles::split_lines(zfiles::slurp(in, "read_impedance_any", name)), name, opt);
  // Notes quote the file (and --columns): JSON needs UTF-8.
  for (auto& n : out.notes) n = zfiles::printable(n);
  out.format_name = zfiles::printable(out.format_name);
  out.quantity = zfiles::printable(out.quantity);
  return out;
}

ImportedImpedance read_impedance_file(const std::string& path, ImpedanceFileFormat hint) {
  ImpedanceReadOptions opt;
  opt.hint = hint;
  return read_impedance_file(path, opt);
}

ImportedImpedance read_impedance_file(const std::string& path, const ImpedanceReadOptions& opt) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open the file");
  return read_impedance_any(in, path, opt);
}

}  // namespace piezo::dsp
