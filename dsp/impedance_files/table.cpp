#include "dsp/impedance_files/table.hpp"

#include <array>
#include <cmath>
#include <optional>

#include "dsp/impedance_files/columns.hpp"
#include "dsp/impedance_files/quantities.hpp"

namespace piezo::dsp {

namespace zfiles {

namespace {

bool is_comment(std::string_view t) {
  t = trim(t);
  return !t.empty() && (t.front() == '#' || t.front() == '!');
}

bool all_digits(std::string_view s) {
  if (s.empty()) return false;
  for (char c : s)
    if (c < '0' || c > '9') return false;
  return true;
}

// "+1" "00000000000e+006" -> 1.00000000000e+006: one number written with a
// decimal comma and split at it by a comma separator.
bool comma_split_halves(std::string_view a, std::string_view b) {
  if (!a.empty() && (a.front() == '+' || a.front() == '-')) a.remove_prefix(1);
  const auto e = b.find_first_of("eE");
  const auto frac = b.substr(0, e);
  if (!all_digits(a) || !all_digits(frac)) return false;
  if (e == std::string_view::npos) return true;
  auto exp = b.substr(e + 1);
  if (!exp.empty() && (exp.front() == '+' || exp.front() == '-')) exp.remove_prefix(1);
  return all_digits(exp);
}

struct Layout {
  char sep = ',';
  bool decimal_comma = false;  // one ',' in a field is the decimal point
  bool joined_halves = false;  // comma separator and decimal comma: fields come in halves
};

void drop_trailing_empty(std::vector<std::string>& f) {
  while (!f.empty() && f.back().empty()) f.pop_back();
}

// The fields of a data row under a layout, halves joined.
std::vector<std::string> row_fields(std::string_view text, const Layout& l) {
  auto f = split_fields(text, l.sep);
  drop_trailing_empty(f);
  if (!l.joined_halves) return f;
  std::vector<std::string> out;
  for (std::size_t i = 0; i + 1 < f.size(); i += 2) out.push_back(f[i] + "." + f[i + 1]);
  if (f.size() % 2) out.push_back(f.back());
  return out;
}

bool all_numbers(const std::vector<std::string>& f, bool decimal_comma) {
  double v;
  for (const auto& x : f)
    if (!parse_number(x, v, decimal_comma)) return false;
  return f.size() >= 2;
}

bool numeric_row(std::string_view text) {
  for (char sep : {'\t', ';', ',', ' '}) {
    auto f = split_fields(text, sep);
    drop_trailing_empty(f);
    if (all_numbers(f, sep != ',')) return true;
  }
  return false;
}

// The separator under which the first data row is numbers with as many fields
// as the header; else the first under which it is numbers at all.
std::optional<Layout> find_layout(const std::vector<std::string>* header_by_sep,
                                  std::string_view row, std::size_t& header_cols) {
  static constexpr std::array<char, 4> kSeps{'\t', ';', ',', ' '};
  std::optional<Layout> fallback;
  for (std::size_t k = 0; k < kSeps.size(); ++k) {
    const char sep = kSeps[k];
    auto f = split_fields(row, sep);
    drop_trailing_empty(f);
    const std::size_t hc = header_by_sep ? header_by_sep[k].size() : f.size();
    if (all_numbers(f, sep != ',')) {
      if (f.size() == hc) {
        header_cols = hc;
        return Layout{sep, sep != ',', false};
      }
      if (!fallback) {
        fallback = Layout{sep, sep != ',', false};
        header_cols = hc;
      }
    }
    if (sep == ',' && header_by_sep && f.size() == 2 * hc && f.size() >= 4) {
      bool halves = true;
      for (std::size_t i = 0; i + 1 < f.size() && halves; i += 2)
        halves = comma_split_halves(f[i], f[i + 1]);
      if (halves) {
        header_cols = hc;
        return Layout{',', false, true};
      }
    }
  }
  return fallback;
}

struct PairChoice {
  PairSpec spec;
  std::size_t col_a = 0, col_b = 0;
  bool quantity_assumed = false;
};

std::optional<PairChoice> choose_pair(const std::vector<ColumnMeaning>& cols) {
  using Q = Quantity;
  using P = Part;
  struct Candidate {
    Q q;
    P a, b;
  };
  static constexpr Candidate kOrder[] = {
      {Q::Z, P::Re, P::Im}, {Q::Z, P::Mag, P::Phase}, {Q::Z, P::MagDb, P::Phase},
      {Q::Y, P::Re, P::Im}, {Q::Y, P::Mag, P::Phase}, {Q::Y, P::MagDb, P::Phase},
      {Q::S, P::Re, P::Im}, {Q::S, P::Mag, P::Phase}, {Q::S, P::MagDb, P::Phase},
      {Q::Z, P::Ls, P::Re}, {Q::Z, P::Cs, P::Re},     {Q::Z, P::Ls, P::D},
      {Q::Z, P::Cs, P::D},  {Q::Z, P::Ls, P::Q},      {Q::Z, P::Cs, P::Q},
      {Q::Y, P::Cp, P::Re}, {Q::Y, P::Lp, P::Re},     {Q::Y, P::Cp, P::Rp},
      {Q::Y, P::Lp, P::Rp}, {Q::Y, P::Cp, P::D},      {Q::Y, P::Lp, P::D},
      {Q::Y, P::Cp, P::Q},  {Q::Y, P::Lp, P::Q},
  };
  const auto find = [&](Q q, P p, std::size_t skip) -> std::optional<std::size_t> {
    for (std::size_t i = 0; i < cols.size(); ++i)
      if (i != skip && cols[i].role == Role::Value && cols[i].part == p &&
          (cols[i].quantity == q || cols[i].quantity == Q::Unknown))
        return i;
    return std::nullopt;
  };
  for (const auto& o : kOrder) {
    const auto a = find(o.q, o.a, cols.size());
    if (!a) continue;
    const auto b = find(o.q, o.b, *a);
    if (!b) continue;
    PairChoice c;
    c.spec = {o.q, o.a, o.b, 50.0};
    c.col_a = *a;
    c.col_b = *b;
    c.quantity_assumed = cols[*a].quantity == Q::Unknown && cols[*b].quantity == Q::Unknown &&
                         (o.a == P::Mag || o.a == P::MagDb || o.a == P::Re);
    return c;
  }
  return std::nullopt;
}

std::string strip_comment_mark(std::string_view t) {
  t = trim(t);
  while (!t.empty() && (t.front() == '#' || t.front() == '!')) t.remove_prefix(1);
  return std::string(trim(t));
}

}  // namespace

ImportedImpedance read_table(const std::vector<TextLine>& lines, const std::string& name,
                             const TableOptions& opt) {
  const char* fn = opt.fn;
  // The first data row, the header above it and the text above that.
  std::size_t first = lines.size();
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (trim(lines[i].text).empty() || is_comment(lines[i].text)) continue;
    if (numeric_row(lines[i].text)) {
      first = i;
      break;
    }
  }
  const TextLine* header = nullptr;
  const TextLine* last_comment = nullptr;
  std::vector<const TextLine*> preamble;
  for (std::size_t i = 0; i < first; ++i) {
    if (trim(lines[i].text).empty()) continue;
    if (is_comment(lines[i].text)) {
      last_comment = &lines[i];
      continue;
    }
    if (header) preamble.push_back(header);
    header = &lines[i];
    last_comment = nullptr;  // a header comment must sit right above the data
  }
  if (first == lines.size()) {
    if (header)
      fail(fn, name, 0, "no data rows under the header '" + std::string(trim(header->text)) + "'");
    fail(fn, name, 0, "no data rows");
  }

  ImportedImpedance meta;
  meta.format = opt.format;
  meta.format_name = opt.format_name;
  std::string header_text;
  int header_line = 0;
  if (header) {
    header_text = header->text;
    header_line = header->number;
  } else if (last_comment) {
    // "! Stimulus(Hz), Z-mag, ..." or "# f_hz re_ohm im_ohm": a header only if it names a
    // frequency.
    const std::string h = strip_comment_mark(last_comment->text);
    for (char sep : {'\t', ';', ',', ' '}) {
      bool has_f = false;
      for (const auto& f : split_fields(h, sep))
        has_f = has_f || classify_column(f).role == Role::Frequency;
      if (has_f) {
        header_text = h;
        header_line = last_comment->number;
        meta.notes.push_back("header taken from the comment on line " +
                             std::to_string(header_line));
        break;
      }
    }
  }
  if (!preamble.empty())
    meta.notes.push_back(std::to_string(preamble.size()) +
                         " line(s) of text above the header skipped (first: '" +
                         std::string(trim(preamble.front()->text)) + "')");

  // Separator, from the header and the first row.
  const TextLine& row0 = lines[first];
  std::array<std::vector<std::string>, 4> hsplit;
  if (!header_text.empty()) {
    const std::array<char, 4> seps{'\t', ';', ',', ' '};
    for (std::size_t k = 0; k < 4; ++k) {
      hsplit[k] = split_fields(header_text, seps[k]);
      drop_trailing_empty(hsplit[k]);
    }
  }
  std::size_t ncols = 0;
  auto layout = find_layout(header_text.empty() ? nullptr : hsplit.data(), row0.text, ncols);
  if (!layout) fail(fn, name, row0.number, "not a row of numbers");
  std::vector<std::string> names;
  if (!header_text.empty()) {
    const std::size_t k = layout->sep == '\t'  ? 0
                          : layout->sep == ';' ? 1
                          : layout->sep == ',' ? 2
                                               : 3;
    names = hsplit[k];
    const std::size_t nrow = row_fields(row0.text, *layout).size();
    if (layout->sep == ' ' && names.size() != nrow) {
      // Blank-separated header with multi-word names: columns apart by 2+ blanks.
      std::vector<std::string> wide;
      std::string t = header_text, cur;
      for (std::size_t i = 0; i <= t.size(); ++i) {
        const bool gap = i == t.size() || (t[i] == '\t') ||
                         (t[i] == ' ' && i + 1 < t.size() && (t[i + 1] == ' ' || t[i + 1] == '\t'));
        if (!gap) {
          cur += t[i];
          continue;
        }
        if (!trim(cur).empty()) wide.emplace_back(trim(cur));
        cur.clear();
        while (i + 1 < t.size() && (t[i + 1] == ' ' || t[i + 1] == '\t')) ++i;
      }
      for (auto& w : wide)
        if (w.size() >= 2 && w.front() == '"' && w.back() == '"') w = w.substr(1, w.size() - 2);
      if (wide.size() == nrow) names = wide;
    }
    ncols = names.size();
  }

  // Columns.
  CurveBuilder b(fn, name);
  b.out = std::move(meta);
  constexpr std::size_t kNone = static_cast<std::size_t>(-1);
  std::vector<ColumnMeaning> cols;
  std::size_t fcol = kNone, smag = kNone, sphase = kNone, kcol = kNone;
  PairChoice pair;
  if (names.empty()) {
    const std::size_t n = row_fields(row0.text, *layout).size();
    if (!opt.allow_headerless) fail(fn, name, row0.number, "data without a header line");
    if (n < 3)
      fail(fn, name, row0.number,
           "no header, and " + std::to_string(n) +
               " columns: a table without a header must be f_hz, re_ohm, im_ohm");
    ncols = n;
    fcol = 0;
    pair.spec = {Quantity::Z, Part::Re, Part::Im, 50.0};
    pair.col_a = 1;
    pair.col_b = 2;
    b.out.notes.push_back("no header: columns read as f_hz, re_ohm, im_ohm" +
                          std::string(n > 3 ? " (further columns ignored)" : ""));
    cols.assign(n, ColumnMeaning{});
    cols[0] = {Role::Frequency, Quantity::Unknown, Part::None, 1.0, true, ""};
    cols[1] = {Role::Value, Quantity::Z, Part::Re, 1.0, true, ""};
    cols[2] = {Role::Value, Quantity::Z, Part::Im, 1.0, true, ""};
  } else {
    for (const auto& h : names) cols.push_back(classify_column(h));
    for (std::size_t i = 0; i < cols.size() && fcol == kNone; ++i)
      if (cols[i].role == Role::Frequency) fcol = i;
    if (fcol == kNone) fail(fn, name, header_line, "no frequency column among " + list(names));
    auto c = choose_pair(cols);
    if (!c)
      fail(fn, name, header_line,
           "no impedance columns among " + list(names) +
               " (need real and imaginary parts, magnitude and phase, R and X, G and B, or an "
               "equivalent circuit such as Cp and D, of Z, Y or S11)");
    pair = *c;
    if (pair.quantity_assumed)
      b.out.notes.push_back(
          "the columns do not say impedance, admittance or S11: read as impedance");
    if (pair.spec.quantity == Quantity::S)
      b.out.notes.push_back("S11 without its reference impedance in the file: z0 = 50 ohm assumed");
    if (!cols[fcol].unit_given) b.out.notes.push_back("frequency unit not given: Hz assumed");
    if (pair.spec.b == Part::Phase && !cols[pair.col_b].unit_given)
      b.out.notes.push_back("phase unit not given: degrees assumed");
    for (std::size_t i = 0; i < cols.size(); ++i) {
      if (cols[i].role == Role::SigmaMag && smag == kNone) smag = i;
      if (cols[i].role == Role::SigmaPhase && sphase == kNone) sphase = i;
      if (cols[i].role == Role::Coverage && kcol == kNone) kcol = i;
    }
    if ((smag != kNone || sphase != kNone) &&
        !(smag != kNone && sphase != kNone && pair.spec.quantity == Quantity::Z)) {
      b.out.notes.push_back(
          "uncertainty columns not read (need both |Z| and phase sigmas of an impedance)");
      smag = sphase = kcol = kNone;
    }
    std::vector<std::string> skipped;
    for (std::size_t i = 0; i < cols.size(); ++i) {
      const bool used =
          i == fcol || i == pair.col_a || i == pair.col_b || i == smag || i == sphase || i == kcol;
      if (!used && !names[i].empty())
        skipped.push_back(names[i] + (cols[i].why.empty() ? "" : " (" + cols[i].why + ")"));
    }
    if (!skipped.empty()) b.out.notes.push_back("columns not read: " + list(skipped));
    b.out.notes.push_back("columns read: " + names[fcol] + ", " + names[pair.col_a] + ", " +
                          names[pair.col_b]);
    if (smag != kNone)
      b.out.notes.push_back("uncertainty read (1 sigma): " + names[smag] + ", " + names[sphase] +
                            (kcol != kNone ? ", coverage factor " + names[kcol] : std::string()));
  }
  b.out.quantity = describe(pair.spec);
  if (layout->joined_halves)
    b.out.notes.push_back("decimal commas with comma separators: each value was split in two");

  // Rows.
  bool comma_used = false;
  double coverage = std::nan("");
  bool coverage_varies = false;
  const auto number = [&](const std::vector<std::string>& f, std::size_t col, int line) {
    double v;
    if (!parse_number(f[col], v, layout->decimal_comma))
      fail(fn, name, line,
           "'" + f[col] + "' is not a number (column " +
               (names.empty() ? std::to_string(col + 1) : "'" + names[col] + "'") + ")");
    if (layout->decimal_comma && f[col].find(',') != std::string::npos) comma_used = true;
    return v;
  };
  for (std::size_t i = first; i < lines.size(); ++i) {
    const auto& L = lines[i];
    if (trim(L.text).empty() || is_comment(L.text)) continue;
    const auto f = row_fields(L.text, *layout);
    if (f.size() != ncols && !(names.empty() && f.size() >= 3))
      fail(fn, name, L.number,
           std::to_string(f.size()) + " columns, the " + (names.empty() ? "first row" : "header") +
               " has " + std::to_string(ncols));
    const double fhz = number(f, fcol, L.number) * cols[fcol].scale;
    const double a = number(f, pair.col_a, L.number) * cols[pair.col_a].scale;
    const double bv = number(f, pair.col_b, L.number) * cols[pair.col_b].scale;
    b.add(L.number, fhz, to_impedance(pair.spec, fhz, a, bv));
    if (smag != kNone)
      b.add_sigma(number(f, smag, L.number) * cols[smag].scale,
                  number(f, sphase, L.number) * cols[sphase].scale);
    if (kcol != kNone) {
      const double k = number(f, kcol, L.number);
      if (std::isnan(coverage))
        coverage = k;
      else if (k != coverage)
        coverage_varies = true;
    }
  }
  if (comma_used) b.out.notes.push_back("decimal commas read as decimal points");
  if (smag != kNone) {
    b.out.coverage_factor = coverage;
    if (coverage_varies)
      b.out.notes.push_back("the coverage factor varies between rows: the first one kept");
  }
  return b.finish();
}

}  // namespace zfiles

ImportedImpedance read_impedance_table(std::istream& in, const std::string& name) {
  const zfiles::TableOptions opt;
  return zfiles::read_table(zfiles::split_lines(zfiles::slurp(in, opt.fn, name)), name, opt);
}

}  // namespace piezo::dsp
