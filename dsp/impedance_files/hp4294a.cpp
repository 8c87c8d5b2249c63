#include "dsp/impedance_files/hp4294a.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <numbers>
#include <optional>
#include <set>

#include "dsp/impedance_files/quantities.hpp"

namespace piezo::dsp {

namespace zfiles {

namespace {

constexpr const char* kFn = "read_hp4294a_text";

struct Trace {
  std::string name;
  int line = 0;
  std::vector<std::string> columns;
  std::vector<std::pair<int, std::vector<double>>> rows;
};

// "KEY: VALUE" of a quoted settings line, key in upper case.
std::optional<std::pair<std::string, std::string>> setting(std::string_view t) {
  t = trim(t);
  if (t.size() < 2 || t.front() != '"' || t.back() != '"') return std::nullopt;
  t = t.substr(1, t.size() - 2);
  const auto colon = t.find(':');
  if (colon == std::string_view::npos || t.find('"') != std::string_view::npos) return std::nullopt;
  std::string key(trim(t.substr(0, colon)));
  for (auto& c : key) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return std::pair{key, std::string(trim(t.substr(colon + 1)))};
}

// The pair of a MEASURE PARAMETER text, with the angle scale.
std::optional<PairSpec> parse_parameter(std::string p, double& angle_scale, bool& angle_given) {
  for (auto& c : p) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  const auto replace_all = [&](std::string_view from, std::string_view to) {
    for (std::size_t i = p.find(from); i != std::string::npos; i = p.find(from, i + to.size()))
      p.replace(i, from.size(), to);
  };
  replace_all("|Z|", " ZMAG ");
  replace_all("|Y|", " YMAG ");
  replace_all("\xCE\xB8", " THETA ");
  replace_all("\xCE\x98", " THETA ");
  std::set<std::string> w;
  std::string cur;
  for (char c : p + ' ') {
    if (std::isalnum(static_cast<unsigned char>(c))) {
      cur += c;
    } else if (!cur.empty()) {
      w.insert(cur);
      cur.clear();
    }
  }
  const auto has = [&](const char* k) { return w.count(k) > 0; };
  angle_given = has("RAD") || has("DEG");
  angle_scale = has("RAD") ? 1.0 : std::numbers::pi / 180.0;
  Quantity q = Quantity::Unknown;
  if (has("IMPEDANCE") || has("ZMAG") || has("Z")) q = Quantity::Z;
  if (has("ADMITTANCE") || has("YMAG") || has("Y")) {
    if (q != Quantity::Unknown) return std::nullopt;
    q = Quantity::Y;
  }
  const bool mag = has("MAG") || has("ZMAG") || has("YMAG");
  if (mag && (has("PHASE") || has("THETA")) && q != Quantity::Unknown)
    return PairSpec{q, Part::Mag, Part::Phase, 50.0};
  if (has("REAL") && has("IMAG") && q != Quantity::Unknown)
    return PairSpec{q, Part::Re, Part::Im, 50.0};
  if (has("R") && has("X")) return PairSpec{Quantity::Z, Part::Re, Part::Im, 50.0};
  if (has("G") && has("B")) return PairSpec{Quantity::Y, Part::Re, Part::Im, 50.0};
  struct Circuit {
    const char* word;
    Part part;
    Quantity quantity;
  };
  static constexpr Circuit kCircuits[] = {{"LS", Part::Ls, Quantity::Z},
                                          {"CS", Part::Cs, Quantity::Z},
                                          {"LP", Part::Lp, Quantity::Y},
                                          {"CP", Part::Cp, Quantity::Y}};
  for (const auto& [word, part, qq] : kCircuits) {
    if (!has(word)) continue;
    const bool series = qq == Quantity::Z;
    if (has("D")) return PairSpec{qq, part, Part::D, 50.0};
    if (has("Q")) return PairSpec{qq, part, Part::Q, 50.0};
    if (series && has("RS")) return PairSpec{qq, part, Part::Re, 50.0};
    if (!series && has("G")) return PairSpec{qq, part, Part::Re, 50.0};
    if (!series && has("RP")) return PairSpec{qq, part, Part::Rp, 50.0};
  }
  return std::nullopt;
}

std::size_t column(const Trace& t, const char* kind) {
  for (std::size_t i = 0; i < t.columns.size(); ++i) {
    const std::string c = lower(t.columns[i]);
    if (c.find("data") != std::string::npos && c.find(kind) != std::string::npos) return i;
  }
  return std::string_view(kind) == "real" ? 1
                                          : 2;  // "Frequency" "Data Trace Real" "Data Trace Imag"
}

}  // namespace

ImportedImpedance read_hp4294a_text(const std::vector<TextLine>& lines, const std::string& name) {
  const char* fn = kFn;
  std::string model, parameter, points_text;
  int parameter_line = 0;
  std::vector<Trace> traces;
  for (const auto& L : lines) {
    const std::string_view t = trim(L.text);
    if (t.empty()) continue;
    if (auto kv = setting(t)) {
      const auto& [key, value] = *kv;
      if (key == "TRACE") {
        traces.push_back({value, L.number, {}, {}});
      } else if (key == "MEASURE PARAMETER") {
        parameter = value;
        parameter_line = L.number;
      } else if (key == "NUMBER OF POINTS") {
        points_text = value;
      }
      continue;
    }
    if (t.front() == '"') {  // a quoted column header
      if (traces.empty()) fail(fn, name, L.number, "column header before any \"TRACE: ...\" line");
      if (!traces.back().rows.empty())
        fail(fn, name, L.number, "column header after the rows of a trace");
      traces.back().columns = split_fields(t, ' ');  // quotes keep "Data Trace Real" whole
      continue;
    }
    std::vector<double> row;
    bool numbers = true;
    for (const auto& f : split_fields(t, ' ')) {
      double v;
      if (!parse_number(f, v)) {
        numbers = false;
        break;
      }
      row.push_back(v);
    }
    if (!numbers) {
      if (traces.empty() && model.empty()) {
        model = std::string(t);  // "4294A REV1.11"
        continue;
      }
      fail(fn, name, L.number,
           "'" + std::string(t.substr(0, 40)) + "' is neither a setting nor a row of numbers");
    }
    if (traces.empty()) fail(fn, name, L.number, "data before any \"TRACE: ...\" line");
    auto& tr = traces.back();
    const std::size_t want = tr.columns.empty() ? 3 : tr.columns.size();
    if (row.size() != want)
      fail(fn, name, L.number,
           std::to_string(row.size()) + " columns, trace " + tr.name + " has " +
               std::to_string(want));
    tr.rows.push_back({L.number, std::move(row)});
  }

  if (parameter.empty()) fail(fn, name, 0, "no \"MEASURE PARAMETER: ...\" line");
  double angle_scale = 1.0;
  bool angle_given = false;
  const auto spec = parse_parameter(parameter, angle_scale, angle_given);
  if (!spec)
    fail(fn, name, parameter_line,
         "MEASURE PARAMETER '" + parameter +
             "' is not read (known: IMPEDANCE or ADMITTANCE MAG PHASE, REAL IMAG, R-X, G-B, "
             "Cs/Ls with Rs/D/Q, Cp/Lp with G/Rp/D/Q)");
  const auto find = [&](const char* n) -> const Trace* {
    for (const auto& t : traces)
      if (iequals(t.name, n)) return &t;
    return nullptr;
  };
  const Trace* A = find("A");
  const Trace* B = find("B");
  if (!A || !B)
    fail(fn, name, 0,
         std::string("no \"TRACE: ") + (A ? "B" : "A") + "\" section: '" + parameter +
             "' needs trace A (" + part_name(spec->a) + ") and trace B (" + part_name(spec->b) +
             ")");
  if (A->rows.size() != B->rows.size())
    fail(fn, name, B->line,
         "trace A has " + std::to_string(A->rows.size()) + " rows, trace B " +
             std::to_string(B->rows.size()));
  if (!points_text.empty()) {
    double n;
    if (parse_number(points_text, n) && n != static_cast<double>(A->rows.size()))
      fail(fn, name, 0,
           "NUMBER of POINTS is " + points_text + " but the traces have " +
               std::to_string(A->rows.size()) + " rows (file cut short?)");
  }

  CurveBuilder b(fn, name);
  const std::size_t ar = column(*A, "real"), br = column(*B, "real");
  for (const Trace* t : {A, B}) {
    const std::size_t re = column(*t, "real"), im = column(*t, "imag");
    for (const auto& [line, row] : t->rows) {
      if (re >= row.size() || im >= row.size())
        fail(fn, name, line, "trace " + t->name + ": no \"Data Trace\" column in this row");
      if (row[im] != 0.0)
        fail(fn, name, line,
             "trace " + t->name +
                 ": the imaginary column is not zero: complex display formats are not "
                 "read (save the traces with a scalar format such as LIN or LOG)");
    }
  }
  const double sa = spec->a == Part::Phase ? angle_scale : 1.0;
  const double sb = spec->b == Part::Phase ? angle_scale : 1.0;
  for (std::size_t k = 0; k < A->rows.size(); ++k) {
    const auto& [la, ra] = A->rows[k];
    const auto& [lb, rb] = B->rows[k];
    if (std::abs(ra[0] - rb[0]) > 1e-9 * std::max(std::abs(ra[0]), std::abs(rb[0])))
      fail(fn, name, lb,
           "trace B's frequency " + std::to_string(rb[0]) + " Hz differs from trace A's " +
               std::to_string(ra[0]) + " Hz (line " + std::to_string(la) + ")");
    b.add(la, ra[0], to_impedance(*spec, ra[0], ra[ar] * sa, rb[br] * sb));
  }
  b.out.format = ImpedanceFileFormat::Hp4294a;
  b.out.format_name = "HP 4294A text" + (model.empty() ? std::string() : " (" + model + ")");
  b.out.quantity = describe(*spec) + " (MEASURE PARAMETER: " + parameter + ")";
  if (spec->b == Part::Phase && !angle_given)
    b.out.notes.push_back("phase unit not given: degrees assumed");
  for (const Trace* t : {A, B})
    if (t->columns.size() > 3) {
      b.out.notes.push_back("memory trace columns ignored");
      break;
    }
  for (const auto& t : traces)
    if (!iequals(t.name, "A") && !iequals(t.name, "B"))
      b.out.notes.push_back("trace " + t.name + " ignored");
  return b.finish();
}

}  // namespace zfiles

ImportedImpedance read_hp4294a_text(std::istream& in, const std::string& name) {
  return zfiles::read_hp4294a_text(zfiles::split_lines(zfiles::slurp(in, zfiles::kFn, name)), name);
}

}  // namespace piezo::dsp
