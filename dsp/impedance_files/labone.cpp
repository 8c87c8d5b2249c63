#include "dsp/impedance_files/labone.hpp"

#include <cctype>
#include <cmath>
#include <algorithm>
#include <optional>

#include "dsp/impedance_files/table.hpp"

namespace piezo::dsp {

namespace zfiles {

namespace {

constexpr const char* kFn = "read_labone";
constexpr std::size_t kScan = 400;  // lines searched for the header

std::string_view uncomment(std::string_view t) {
  t = trim(t);
  while (!t.empty() && t.front() == '%') t.remove_prefix(1);
  return trim(t);
}

// The fields of a line under the separator that gives the most of them.
std::pair<std::vector<std::string>, char> best_split(std::string_view t) {
  std::vector<std::string> best;
  char sep = ';';
  for (char s : {';', '\t', ',', ' '}) {
    auto f = split_fields(t, s);
    if (f.size() > best.size()) {
      best = std::move(f);
      sep = s;
    }
  }
  return {best, sep};
}

bool has_field(const std::vector<std::string>& f, std::string_view w) {
  for (const auto& x : f)
    if (iequals(x, w)) return true;
  return false;
}

bool impedance_field(const std::vector<std::string>& f) {
  for (const char* w : {"realz", "imagz", "absz", "phasez", "param0", "param1"})
    if (has_field(f, w)) return true;
  return false;
}

std::optional<std::size_t> index_of(const std::vector<std::string>& f, std::string_view w) {
  for (std::size_t i = 0; i < f.size(); ++i)
    if (iequals(f[i], w)) return i;
  return std::nullopt;
}

// The two parameters of a "representation" line, in order, in our vocabulary.
std::optional<std::pair<std::string, std::string>> representation(
    const std::vector<TextLine>& lines, std::size_t end, int& line) {
  for (std::size_t i = 0; i < end; ++i) {
    const std::string l = lower(lines[i].text);
    const auto k = l.find("representation");
    if (k == std::string::npos) continue;
    std::vector<std::string> words;
    std::string cur;
    for (char c : lines[i].text.substr(k + 14) + " ") {
      if (std::isalnum(static_cast<unsigned char>(c)) || c == '|') {
        cur += c;
      } else if (!cur.empty()) {
        words.push_back(cur);
        cur.clear();
      }
    }
    std::vector<std::string> params;
    for (const auto& w : words) {
      const std::string u = lower(w);
      const char* p = u == "cs" ? "Cs"
                      : u == "cp" ? "Cp"
                      : u == "ls" ? "Ls"
                      : u == "lp" ? "Lp"
                      : u == "rs" || u == "r" ? "Rs"
                      : u == "rp" ? "Rp"
                      : u == "d" ? "D"
                      : u == "q" ? "Q"
                      : u == "x" ? "X"
                      : u == "g" ? "G"
                      : u == "b" ? "B"
                      : u == "|z|" || u == "z" || u == "absz" ? "|Z|[ohm]"
                      : u == "|y|" || u == "y" ? "|Y|[S]"
                      : u == "theta" || u == "phase" || u == "phasez" ? "phase Z[rad]"
                                                                      : nullptr;
      if (p) params.emplace_back(p);
      if (params.size() == 2) break;
    }
    if (params.size() == 2) {
      line = lines[i].number;
      return std::pair{params[0], params[1]};
    }
  }
  return std::nullopt;
}

// LabOne's native sweeper CSV is transposed: a header "chunk;timestamp;size;fieldname"
// and one row per chunk and field ("1;120126...;150;realz;v1;v2;..."). The last
// chunk with a finite frequency becomes an ordinary table (one row per point, the
// line of its frequency row as every point's line); nothing when the file is not so.
std::optional<std::vector<TextLine>> untranspose(const std::vector<TextLine>& lines,
                                                 std::vector<std::string>& notes) {
  std::size_t h = lines.size();
  for (std::size_t i = 0; i < lines.size() && i < kScan && h == lines.size(); ++i) {
    const auto f = split_fields(trim(lines[i].text), ';');
    if (f.size() >= 4 && iequals(f[0], "chunk") && iequals(f[3], "fieldname")) h = i;
  }
  if (h == lines.size()) return std::nullopt;
  struct Field {
    std::string name;
    int line = 0;
    std::vector<std::string> values;
  };
  struct Chunk {
    std::string id;
    std::vector<Field> fields;
  };
  std::vector<Chunk> chunks;
  for (std::size_t i = h + 1; i < lines.size(); ++i) {
    auto f = split_fields(trim(lines[i].text), ';');
    if (f.size() < 5 || iequals(f[0], "chunk")) continue;  // blank, or the header again
    while (f.size() > 4 && f.back().empty()) f.pop_back();
    if (chunks.empty() || chunks.back().id != f[0]) chunks.push_back({f[0], {}});
    chunks.back().fields.push_back({f[3], lines[i].number, {f.begin() + 4, f.end()}});
  }
  // The last complete sweep (every frequency and realz finite), else the last
  // with any finite frequency.
  const auto field = [](const Chunk& ch, std::string_view name) -> const Field* {
    for (const auto& fl : ch.fields)
      if (iequals(fl.name, name)) return &fl;
    return nullptr;
  };
  const auto finite_count = [](const Field* fl) {
    std::size_t n = 0;
    for (std::size_t k = 0; fl && k < fl->values.size(); ++k) {
      double v;
      n += parse_number(fl->values[k], v) && std::isfinite(v);
    }
    return n;
  };
  std::size_t pick = chunks.size();
  for (std::size_t c = chunks.size(); c-- > 0 && pick == chunks.size();) {
    const auto* f = field(chunks[c], "frequency");
    const auto* z = field(chunks[c], "realz") ? field(chunks[c], "realz") : field(chunks[c], "absz");
    if (f && finite_count(f) == f->values.size() && (!z || finite_count(z) == z->values.size()))
      pick = c;
  }
  for (std::size_t c = chunks.size(); c-- > 0 && pick == chunks.size();)
    if (finite_count(field(chunks[c], "frequency")) > 0) pick = c;
  if (pick < chunks.size()) {
    const std::size_t c = pick;
    const auto& ch = chunks[c];
    const Field* freq = field(ch, "frequency");
    std::vector<TextLine> out;
    std::string header;
    std::size_t n = 0;
    for (const auto& fl : ch.fields) {
      header += (header.empty() ? "" : ";") + fl.name;
      n = std::max(n, fl.values.size());
    }
    out.push_back({lines[h].number, header});
    for (std::size_t k = 0; k < n; ++k) {
      std::string row;
      for (std::size_t j = 0; j < ch.fields.size(); ++j) {
        const auto& v = ch.fields[j].values;
        row += (j ? ";" : "") + (k < v.size() && !v[k].empty() ? v[k] : std::string("nan"));
      }
      out.push_back({freq->line, row});
    }
    notes.push_back("LabOne's transposed layout (one row per field): chunk " + ch.id + " read, " +
                    std::to_string(chunks.size()) + " chunk(s) (sweeps) in the file" +
                    (c + 1 < chunks.size() ? " (the last complete sweep; later ones are not)" : ""));
    return out;
  }
  return std::vector<TextLine>{lines[h]};  // no chunk with a frequency: "no data rows"
}

}  // namespace

bool labone_file(const std::vector<TextLine>& lines) {
  for (std::size_t i = 0; i < lines.size() && i < kScan; ++i) {
    const auto t = trim(lines[i].text);
    if (t.empty()) continue;
    if (t.front() == '%') {
      const std::string l = lower(t);
      if (l.find("labone") != std::string::npos || l.find("zurich instruments") != std::string::npos)
        return true;
    }
    const auto f = best_split(uncomment(t)).first;
    if (impedance_field(f) || (has_field(f, "chunk") && has_field(f, "timestamp")) ||
        (f.size() >= 4 && iequals(f[0], "chunk") && iequals(f[3], "fieldname")))
      return true;
  }
  return false;
}

ImportedImpedance read_labone(const std::vector<TextLine>& all, const std::string& name) {
  std::vector<std::string> notes;
  const auto transposed = untranspose(all, notes);
  const auto& lines = transposed ? *transposed : all;
  // The header: the first line (a '%' comment or not) with a frequency (or grid) column.
  std::size_t h = lines.size();
  std::vector<std::string> fields;
  char sep = ';';
  for (std::size_t i = 0; i < lines.size() && i < kScan && h == lines.size(); ++i) {
    auto [f, s] = best_split(uncomment(lines[i].text));
    // A column header, not prose that mentions a frequency: it names LabOne's columns too.
    const bool labone_columns = impedance_field(f) || has_field(f, "chunk") ||
                                has_field(f, "x") || has_field(f, "r");
    if ((has_field(f, "frequency") || has_field(f, "grid")) && labone_columns) {
      h = i;
      fields = std::move(f);
      sep = s;
    }
  }
  if (h == lines.size())
    fail(kFn, name, 0,
         "no header line naming the columns (frequency;realz;imagz;... as LabOne writes it)" +
             std::string(kColumnsHint));

  auto fcol = index_of(fields, "frequency");
  if (!fcol) {
    fcol = index_of(fields, "grid");
    notes.push_back("no frequency column: the sweep grid read as the frequency in Hz");
  }
  std::vector<std::string> cols(fields.size(), "-");
  cols[*fcol] = "f[Hz]";
  std::vector<std::size_t> used{*fcol};
  const auto re = index_of(fields, "realz"), im = index_of(fields, "imagz");
  const auto ab = index_of(fields, "absz"), ph = index_of(fields, "phasez");
  const auto p0 = index_of(fields, "param0"), p1 = index_of(fields, "param1");
  int rep_line = 0;
  std::optional<std::pair<std::string, std::string>> rep;
  if (p0 && p1) rep = representation(lines, lines.size(), rep_line);
  if (re && im) {
    cols[*re] = "re Z[ohm]";
    cols[*im] = "im Z[ohm]";
    used.insert(used.end(), {*re, *im});
  } else if (ab && ph) {
    cols[*ab] = "|Z|[ohm]";
    cols[*ph] = "phase Z[rad]";
    used.insert(used.end(), {*ab, *ph});
    notes.push_back("phasez read in radians (LabOne's unit)");
  } else if (p0 && p1 && rep) {
    cols[*p0] = rep->first;
    cols[*p1] = rep->second;
    used.insert(used.end(), {*p0, *p1});
    notes.push_back("param0, param1 read as " + rep->first + ", " + rep->second +
                    " (the representation on line " + std::to_string(rep_line) + ")");
  } else if (ab) {
    cols[*ab] = "|Z|[ohm]";
    used.push_back(*ab);
  } else {
    std::string what = "no impedance among the columns " + list(fields);
    if (p0 || p1)
      what += ": param0/param1 without a line stating their representation (e.g. "
              "\"% representation: Cp D\"); export realz and imagz, or name the columns with "
              "--columns";
    else if (has_field(fields, "x") || has_field(fields, "r"))
      what += ": demodulator signals (x, y, r, phase: volts) are not an impedance; save the "
              "Impedance Analyzer's sweep (realz, imagz) instead";
    else
      what += std::string(" (need realz and imagz, or absz and phasez)") + kColumnsHint;
    fail(kFn, name, lines[h].number, what);
  }

  // The data rows: the last chunk, measured points only.
  const auto chunk = index_of(fields, "chunk");
  std::vector<TextLine> data;
  std::string last_chunk;
  std::size_t chunks = 0, unmeasured = 0;
  const auto finite_fields = [&](const std::vector<std::string>& f) {
    for (const auto k : used) {
      double v;
      if (k < f.size() && parse_number(f[k], v, sep != ',') && !std::isfinite(v)) return false;
    }
    return true;
  };
  for (std::size_t i = h + 1; i < lines.size(); ++i) {
    const auto t = trim(lines[i].text);
    if (t.empty() || t.front() == '%') continue;
    const auto f = split_fields(t, sep);
    if (chunk && *chunk < f.size() && f[*chunk] != last_chunk) {
      ++chunks;
      last_chunk = f[*chunk];
      data.clear();
      unmeasured = 0;
    }
    if (!finite_fields(f)) {
      ++unmeasured;
      continue;
    }
    data.push_back(lines[i]);
  }
  if (chunks > 1)
    notes.push_back(std::to_string(chunks) + " sweeps in the file (chunk column): the last one (" +
                    last_chunk + ") read");
  if (unmeasured > 0)
    notes.push_back(std::to_string(unmeasured) + " point(s) without a value (nan) left out");

  TableOptions opt;
  opt.fn = kFn;
  opt.format = ImpedanceFileFormat::LabOne;
  opt.format_name = "Zurich Instruments LabOne export";
  opt.allow_headerless = false;
  opt.columns = cols;
  opt.labels = fields;
  opt.columns_origin = "the header";
  opt.header_line = lines[h].number;
  auto out = read_table(data, name, opt);
  out.notes.insert(out.notes.begin(), "header on line " + std::to_string(lines[h].number));
  out.notes.insert(out.notes.end(), notes.begin(), notes.end());
  return out;
}

}  // namespace zfiles

ImportedImpedance read_labone(std::istream& in, const std::string& name) {
  return zfiles::read_labone(zfiles::split_lines(zfiles::slurp(in, zfiles::kFn, name)), name);
}

}  // namespace piezo::dsp
