#include "dsp/impedance_files/hioki.hpp"

#include <cctype>
#include <optional>

#include "dsp/impedance_files/table.hpp"

namespace piezo::dsp {

namespace zfiles {

namespace {

constexpr const char* kFn = "read_hioki_csv";

bool non_ascii(std::string_view s) {
  for (char c : s)
    if (static_cast<unsigned char>(c) >= 0x80) return true;
  return false;
}

std::string upper(std::string_view s) {
  std::string u(s);
  for (auto& c : u) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return u;
}

// The fields of a header line under sep, or nothing when it is not a HIOKI header.
std::optional<std::vector<std::string>> header_fields(std::string_view line, char sep) {
  auto f = split_fields(line, sep);
  if (f.size() < 2) return std::nullopt;
  const std::string first = upper(f[0]);
  if (first != "NO." && first != "NO") return std::nullopt;
  if (!istarts_with(f[1], "FREQ")) return std::nullopt;
  return f;
}

struct Column {
  std::string spec;  // our vocabulary ("|Z|[ohm]"), "-" when not read
  std::string why;   // why a parameter is not read
};

// One parameter header ("Z[Ω]", "θ[deg]", "Cs[F]", "OFF") in our vocabulary.
Column parameter(const std::string& text) {
  std::string_view t = trim(text);
  std::string_view unit;
  if (const auto open = t.find_first_of("[("); open != std::string_view::npos) {
    const auto close = t.find_first_of("])", open + 1);
    unit = trim(t.substr(open + 1, (close == std::string_view::npos ? t.size() : close) - open - 1));
    t = trim(t.substr(0, open));
  }
  const std::string p = upper(t);
  if (p.empty() || p == "OFF") return {"-", ""};
  // The unit's ASCII prefix (k, m, u, n, p, M) before a non-ASCII symbol (Ω, µ).
  std::string prefix;
  bool symbol = false;
  for (char c : unit) {
    if (static_cast<unsigned char>(c) >= 0x80) {
      symbol = true;
      break;
    }
    prefix += c;
  }
  const auto with_unit = [&](const char* q, const char* si) {
    if (unit.empty()) return std::string(q);
    if (!symbol) return std::string(q) + "[" + std::string(unit) + "]";
    // "kΩ" -> "kohm"; "µS" (a non-ASCII prefix before S) -> "uS".
    if (std::string_view(si) == "ohm") return std::string(q) + "[" + prefix + "ohm]";
    const char last = unit.back();
    if (last == 'S' || last == 'F' || last == 'H')
      return std::string(q) + "[" + prefix + "u" + std::string(1, last) + "]";
    return std::string(q) + "[" + si + "]";
  };
  if (p == "Z") return {with_unit("|Z|", "ohm"), ""};
  if (p == "Y") return {with_unit("|Y|", "S"), ""};
  if (p == "RS" || p == "R") return {with_unit("Rs", "ohm"), ""};
  if (p == "RP") return {with_unit("Rp", "ohm"), ""};
  if (p == "X") return {with_unit("X", "ohm"), ""};
  if (p == "G") return {with_unit("G", "S"), ""};
  if (p == "B") return {with_unit("B", "S"), ""};
  if (p == "CS") return {with_unit("Cs", "F"), ""};
  if (p == "CP") return {with_unit("Cp", "F"), ""};
  if (p == "LS") return {with_unit("Ls", "H"), ""};
  if (p == "LP") return {with_unit("Lp", "H"), ""};
  if (p == "D") return {"D", ""};
  if (p == "Q") return {"Q", ""};
  // θ: written in Shift-JIS (0x83 0xC6) or UTF-8, or spelled out; degrees unless "rad".
  if (p == "THETA" || p == "PHASE" || (non_ascii(p) && p.size() <= 3)) {
    const std::string u = lower(unit);
    return {u.find("rad") != std::string::npos ? "theta Z[rad]" : "theta Z[deg]", ""};
  }
  if (p == "RDC") return {"-", "DC resistance, not an impedance"};
  return {"-", "not a parameter we know"};
}

// A label for messages: Shift-JIS Ω, θ, °, µ as UTF-8, other bytes above 0x7F as '?'.
std::string label(std::string_view s) {
  std::string out;
  for (std::size_t i = 0; i < s.size(); ++i) {
    const auto c = static_cast<unsigned char>(s[i]);
    if (c < 0x80) {
      out += s[i];
      continue;
    }
    const auto next = i + 1 < s.size() ? static_cast<unsigned char>(s[i + 1]) : 0;
    if (c == 0x83 && next == 0xB6) {
      out += "\xCE\xA9";
    } else if (c == 0x83 && next == 0xC6) {
      out += "\xCE\xB8";
    } else if (c == 0x81 && next == 0x8B) {
      out += "\xC2\xB0";
    } else if (c == 0x83 && next == 0xCA) {
      out += "\xC2\xB5";
    } else {
      out += '?';
      continue;
    }
    ++i;
  }
  return out;
}

// "IM3570" in the settings above the header, when there.
std::string model(const std::vector<TextLine>& lines, std::size_t header) {
  for (std::size_t i = 0; i < header; ++i) {
    const std::string u = upper(lines[i].text);
    for (std::size_t k = u.find("IM"); k != std::string::npos; k = u.find("IM", k + 1)) {
      std::size_t e = k + 2;
      while (e < u.size() && std::isdigit(static_cast<unsigned char>(u[e]))) ++e;
      if (e - k == 6) return u.substr(k, 6);
    }
  }
  return "";
}

}  // namespace

bool hioki_header(std::string_view line) {
  for (char sep : {',', ';', '\t'})
    if (header_fields(line, sep)) return true;
  return false;
}

ImportedImpedance read_hioki_csv(const std::vector<TextLine>& lines, const std::string& name) {
  std::size_t h = lines.size();
  std::vector<std::string> fields;
  for (std::size_t i = 0; i < lines.size() && h == lines.size(); ++i)
    for (char s : {',', ';', '\t'})
      if (auto f = header_fields(lines[i].text, s)) {
        h = i;
        fields = *f;
        break;
      }
  if (h == lines.size())
    fail(kFn, name, 0, "no header line \"No.\",\"FREQUENCY(Hz)\",... (a HIOKI sweep saved as CSV)");

  TableOptions opt;
  opt.fn = kFn;
  opt.format = ImpedanceFileFormat::Hioki;
  const std::string m = model(lines, h);
  opt.format_name = "HIOKI " + (m.empty() ? std::string() : m + " ") + "CSV";
  opt.allow_headerless = false;
  opt.columns_origin = "the header";
  opt.header_line = lines[h].number;
  std::vector<std::string> not_read;
  bool theta = false;
  for (std::size_t k = 0; k < fields.size(); ++k) {
    opt.labels.push_back(label(fields[k]));
    if (k == 0) {
      opt.columns.push_back("-");
    } else if (k == 1) {
      opt.columns.push_back(label(fields[k]));  // "FREQUENCY(Hz)"
    } else {
      auto c = parameter(fields[k]);
      theta = theta || c.spec.rfind("theta", 0) == 0;
      if (!c.why.empty()) not_read.push_back(opt.labels.back() + " (" + c.why + ")");
      opt.columns.push_back(c.spec);
    }
  }
  while (opt.columns.size() > 2 && opt.columns.back() == "-" && opt.labels.back().empty()) {
    opt.columns.pop_back();
    opt.labels.pop_back();
  }
  const std::vector<TextLine> data(lines.begin() + static_cast<std::ptrdiff_t>(h) + 1, lines.end());
  auto out = read_table(data, name, opt);
  out.notes.insert(out.notes.begin(), "header on line " + std::to_string(lines[h].number) + ", " +
                                          std::to_string(h) + " line(s) of settings above it");
  if (theta) out.notes.push_back("theta read as the phase of Z (HIOKI's convention)");
  if (!not_read.empty()) out.notes.push_back("parameters not read: " + list(not_read));
  return out;
}

}  // namespace zfiles

ImportedImpedance read_hioki_csv(std::istream& in, const std::string& name) {
  return zfiles::read_hioki_csv(zfiles::split_lines(zfiles::slurp(in, zfiles::kFn, name)), name);
}

}  // namespace piezo::dsp
