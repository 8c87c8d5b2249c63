#include "dsp/impedance_files/e4990a.hpp"

#include <stdexcept>

#include "dsp/impedance_files/table.hpp"

namespace piezo::dsp {

namespace zfiles {

namespace {
constexpr const char* kFn = "read_e4990a_csv";

struct Block {
  std::string title;  // "CH1_DATA"
  int line = 0;
  std::vector<TextLine> lines;
};
}  // namespace

bool e4990a_begin_line(std::string_view line) {
  line = trim(line);
  if (!istarts_with(line, "BEGIN")) return false;
  line = trim(line.substr(5));
  return istarts_with(line, "CH") && line.size() > 2;
}

ImportedImpedance read_e4990a_csv(const std::vector<TextLine>& lines, const std::string& name) {
  const char* fn = kFn;
  std::string instrument;
  std::vector<Block> blocks;
  bool open = false;
  int outside = 0;
  for (const auto& L : lines) {
    const std::string_view t = trim(L.text);
    if (!open) {
      if (t.empty()) continue;
      if (t.front() == '!') {
        if (instrument.empty()) instrument = std::string(trim(t.substr(1)));
        continue;
      }
      if (istarts_with(t, "BEGIN")) {
        blocks.push_back({std::string(trim(t.substr(5))), L.number, {}});
        open = true;
        continue;
      }
      ++outside;
      continue;
    }
    if (iequals(t, "END")) {
      open = false;
      continue;
    }
    blocks.back().lines.push_back(L);
  }
  if (blocks.empty()) fail(fn, name, 0, "no BEGIN ... END block (\"BEGIN CH1_DATA\")");
  if (open)
    fail(fn, name, blocks.back().line,
         "BEGIN " + blocks.back().title + " has no END (file cut short?)");

  const bool e4990a = instrument.find("E4990") != std::string::npos;
  TableOptions opt;
  opt.fn = fn;
  opt.format = ImpedanceFileFormat::E4990a;
  opt.format_name = e4990a ? "Keysight E4990A CSV" : "Keysight CSV (BEGIN/END blocks)";
  if (!instrument.empty()) opt.format_name += " (" + instrument + ")";
  opt.allow_headerless = false;

  std::vector<std::string> failures;
  for (std::size_t k = 0; k < blocks.size(); ++k) {
    try {
      auto out = read_table(blocks[k].lines, name, opt);
      out.notes.insert(out.notes.begin(), "block " + blocks[k].title + " (line " +
                                              std::to_string(blocks[k].line) + ") read");
      for (std::size_t j = 0; j < failures.size(); ++j) out.notes.push_back(failures[j]);
      for (std::size_t j = k + 1; j < blocks.size(); ++j)
        out.notes.push_back("block " + blocks[j].title + " (line " +
                            std::to_string(blocks[j].line) + ") not read");
      if (outside > 0)
        out.notes.push_back(std::to_string(outside) +
                            " line(s) outside the BEGIN ... END blocks ignored");
      return out;
    } catch (const std::invalid_argument& e) {
      if (blocks.size() == 1) throw;
      failures.push_back("block " + blocks[k].title + " not read: " + e.what());
    }
  }
  std::string all;
  for (const auto& f : failures) all += (all.empty() ? "" : "; ") + f;
  fail(fn, name, 0, "no block holds an impedance: " + all);
}

}  // namespace zfiles

ImportedImpedance read_e4990a_csv(std::istream& in, const std::string& name) {
  return zfiles::read_e4990a_csv(zfiles::split_lines(zfiles::slurp(in, zfiles::kFn, name)), name);
}

}  // namespace piezo::dsp
