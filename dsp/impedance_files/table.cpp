#include "dsp/impedance_files/table.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <optional>

#include "dsp/impedance_files/columns.hpp"
#include "dsp/impedance_files/lcr_parameters.hpp"
#include "dsp/impedance_files/quantities.hpp"

namespace piezo::dsp {

namespace zfiles {

const char* const kColumnsHint =
    "; name the columns with --columns (piezobench figures), e.g. --columns f[Hz],R[ohm],X[ohm] "
    "or --columns f[kHz],G[uS],B[uS]";

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

std::optional<PairChoice> choose_pair(const std::vector<ColumnMeaning>& cols,
                                      bool allow_s21 = true) {
  using Q = Quantity;
  using P = Part;
  struct Candidate {
    Q q;
    P a, b;
  };
  static constexpr Candidate kOrder[] = {
      {Q::Z, P::Re, P::Im}, {Q::Z, P::Mag, P::Phase}, {Q::Z, P::MagDb, P::Phase},
      {Q::Y, P::Re, P::Im}, {Q::Y, P::Mag, P::Phase}, {Q::Y, P::MagDb, P::Phase},
      {Q::S21, P::Re, P::Im}, {Q::S21, P::Mag, P::Phase}, {Q::S21, P::MagDb, P::Phase},
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
  // A transmission export: S21 first (a program's Z columns beside it are
  // derived from it, vna/J's printed in a width that drops digits).
  bool s21_columns = false;
  for (const auto& c : cols) s21_columns = s21_columns || c.quantity == Q::S21;
  std::vector<Candidate> order;
  if (s21_columns && allow_s21)
    for (const auto& o : kOrder)
      if (o.q == Q::S21) order.push_back(o);
  for (const auto& o : kOrder)
    if (o.q != Q::S21 || (allow_s21 && !s21_columns)) order.push_back(o);
  for (const auto& o : order) {
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

// The parameter a column holds, for lcr_parameters.hpp.
std::optional<Lcr> lcr_of(const ColumnMeaning& c) {
  if (c.role != Role::Value) return std::nullopt;
  const auto q = c.quantity;
  switch (c.part) {
    case Part::Mag:
      if (q == Quantity::Z) return Lcr::AbsZ;
      if (q == Quantity::Y) return Lcr::AbsY;
      return std::nullopt;
    case Part::Phase:
      if (q == Quantity::Y) return Lcr::PhaseY;
      if (q == Quantity::Z || q == Quantity::Unknown) return Lcr::Phase;
      return std::nullopt;
    case Part::Re:
      if (q == Quantity::Z) return Lcr::R;
      if (q == Quantity::Y) return Lcr::G;
      return std::nullopt;
    case Part::Im:
      if (q == Quantity::Z) return Lcr::X;
      if (q == Quantity::Y) return Lcr::B;
      return std::nullopt;
    case Part::Rp:
      return Lcr::Rp;
    case Part::Cs:
      return Lcr::Cs;
    case Part::Cp:
      return Lcr::Cp;
    case Part::Ls:
      return Lcr::Ls;
    case Part::Lp:
      return Lcr::Lp;
    case Part::D:
      return Lcr::D;
    case Part::Q:
      return Lcr::Q;
    default:
      return std::nullopt;
  }
}

constexpr std::size_t kNoCol = static_cast<std::size_t>(-1);

struct LcrChoice {
  LcrPair pair;
  std::size_t col_a = 0, col_b = kNoCol;
};

// Two columns that give complex Z, else two or one that give |Z|.
std::optional<LcrChoice> choose_lcr(const std::vector<ColumnMeaning>& cols) {
  std::optional<LcrChoice> magnitude;
  for (std::size_t i = 0; i < cols.size(); ++i) {
    const auto a = lcr_of(cols[i]);
    if (!a) continue;
    for (std::size_t j = i + 1; j < cols.size(); ++j) {
      const auto b = lcr_of(cols[j]);
      if (!b) continue;
      if (auto p = lcr_pair(*a, *b)) {
        if (!p->magnitude_only) return LcrChoice{*p, i, j};
        if (!magnitude) magnitude = LcrChoice{*p, i, j};
      }
    }
  }
  if (magnitude) return magnitude;
  for (std::size_t i = 0; i < cols.size(); ++i)
    if (const auto a = lcr_of(cols[i]))
      if (auto p = lcr_pair(*a, std::nullopt)) return LcrChoice{*p, i, kNoCol};
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
  const bool given = !opt.columns.empty();
  if (given) {
    header_line = opt.header_line;
    // Names given: the header (if any) is text above the data like the rest.
    if (header) preamble.push_back(header);
    header = nullptr;
    last_comment = nullptr;
  }
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
    meta.notes.push_back(std::to_string(preamble.size()) + " line(s) of text above the " +
                         (given ? "data" : "header") + " skipped (first: '" +
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
  } else if (given) {
    hsplit.fill(opt.columns);
  }
  std::size_t ncols = 0;
  auto layout =
      find_layout(header_text.empty() && !given ? nullptr : hsplit.data(), row0.text, ncols);
  if (!layout) fail(fn, name, row0.number, "not a row of numbers");
  std::vector<std::string> names;
  if (given) {
    names = opt.columns;
    ncols = names.size();
  } else if (!header_text.empty()) {
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
  constexpr std::size_t kNone = kNoCol;
  std::vector<ColumnMeaning> cols;
  std::size_t fcol = kNone, smag = kNone, sphase = kNone, kcol = kNone;
  PairChoice pair;
  std::optional<LcrChoice> lcr;
  // What a column is called in messages: the instrument's name, else the header's.
  const auto label = [&](std::size_t i) {
    return i < opt.labels.size() && !opt.labels[i].empty() ? opt.labels[i] : names[i];
  };
  std::vector<std::string> labels;
  if (names.empty()) {
    const std::size_t n = row_fields(row0.text, *layout).size();
    if (!opt.allow_headerless) fail(fn, name, row0.number, "data without a header line");
    if (n != 3) {
      std::string spec = "f[Hz],R[ohm],X[ohm]";
      for (std::size_t k = 3; k < n && k < 16; ++k) spec += ",-";
      fail(fn, name, row0.number,
           "no header, and " + std::to_string(n) + " columns: a table without a header is read " +
               "only as the three columns f_hz, re_ohm, im_ohm; name the columns with --columns " +
               "(piezobench figures), e.g. --columns " +
               (n > 3 ? spec + " or f[Hz],|Z|[ohm],theta[deg]" + spec.substr(19)
                      : std::string("f[Hz],|Z|[ohm] (a magnitude alone)")));
    }
    ncols = n;
    fcol = 0;
    pair.spec = {Quantity::Z, Part::Re, Part::Im, 50.0};
    pair.col_a = 1;
    pair.col_b = 2;
    b.out.notes.push_back("no header: columns read as f_hz, re_ohm, im_ohm");
    cols.assign(n, ColumnMeaning{});
    cols[0] = {Role::Frequency, Quantity::Unknown, Part::None, 1.0, true, ""};
    cols[1] = {Role::Value, Quantity::Z, Part::Re, 1.0, true, ""};
    cols[2] = {Role::Value, Quantity::Z, Part::Im, 1.0, true, ""};
  } else {
    std::vector<std::string> negated;
    for (const auto& h : names) {
      if (given && h.size() > 1 && h.front() == '-') {  // "-theta(deg)": the column negated
        cols.push_back(classify_column(std::string_view(h).substr(1)));
        cols.back().scale = -cols.back().scale;
        negated.push_back(h.substr(1));
        continue;
      }
      cols.push_back(classify_column(h));
    }
    if (!negated.empty()) b.out.notes.push_back("negated as asked: " + list(negated));
    for (std::size_t i = 0; i < names.size(); ++i) labels.push_back(label(i));
    const std::string hint = given ? std::string() : std::string(kColumnsHint);
    for (std::size_t i = 0; i < cols.size() && fcol == kNone; ++i)
      if (cols[i].role == Role::Frequency) fcol = i;
    if (fcol == kNone)
      fail(fn, name, header_line, "no frequency column among " + list(labels) + hint);
    auto c = choose_pair(cols);
    if (!c) lcr = choose_lcr(cols);
    if (!c && !lcr) {
      std::vector<std::string> known;
      for (std::size_t i = 0; i < cols.size(); ++i)
        if (lcr_of(cols[i])) known.push_back(labels[i]);
      if (!known.empty())
        fail(fn, name, header_line,
             "the columns give " + list(known) +
                 ": neither complex Z nor |Z| (a second parameter is needed, such as X or B "
                 "with R or G, the phase with |Z|, D with Cs or Cp; or |Z| alone for a "
                 "magnitude-only fit)");
      fail(fn, name, header_line,
           "no impedance columns among " + list(labels) +
               " (need real and imaginary parts, magnitude and phase, R and X, G and B, or an "
               "equivalent circuit such as Cp and D, of Z, Y, S11 or S21)" + hint);
    }
    if (c) pair = *c;
    std::string s21_note;
    if (c && pair.spec.quantity == Quantity::S21) {
      // A transmission export: S21 unless nothing passes (median |S21| below
      // -60 dB: the device is on port 1), then S11 when the file has it.
      std::vector<double> mags;
      for (std::size_t i = first; i < lines.size(); ++i) {
        if (trim(lines[i].text).empty() || is_comment(lines[i].text)) continue;
        const auto f = row_fields(lines[i].text, *layout);
        double va, vb;
        if (f.size() <= std::max(pair.col_a, pair.col_b) ||
            !parse_number(f[pair.col_a], va, layout->decimal_comma) ||
            !parse_number(f[pair.col_b], vb, layout->decimal_comma))
          continue;
        va *= cols[pair.col_a].scale;
        vb *= cols[pair.col_b].scale;
        mags.push_back(pair.spec.a == Part::Re    ? std::hypot(va, vb)
                       : pair.spec.a == Part::Mag ? std::abs(va)
                                                  : std::pow(10.0, va / 20.0));
      }
      // "Transmission Loss(dB)" written as a positive loss: -dB.
      if (pair.spec.a == Part::MagDb && cols[pair.col_a].loss && !mags.empty() &&
          std::all_of(mags.begin(), mags.end(), [](double m) { return m >= 1.0; }) &&
          std::any_of(mags.begin(), mags.end(), [](double m) { return m > 1.0; })) {
        cols[pair.col_a].scale = -cols[pair.col_a].scale;
        for (auto& m : mags) m = 1.0 / m;
        s21_note = "transmission loss written positive: read as |S21| = -loss (dB); ";
      }
      const auto median_of = [](std::vector<double> v) {
        if (v.empty()) return 0.0;
        std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
        return v[v.size() / 2];
      };
      const double median = median_of(mags);
      char db[32];
      std::snprintf(db, sizeof db, "%.3g", 20 * std::log10(std::max(median, 1e-300)));
      const auto s11 = choose_pair(cols, false);
      // With S11 beside it: one element in series between the ports has S11 + S21 = 1.
      double series_misfit = 0;
      if (s11 && s11->spec.quantity == Quantity::S) {
        const auto value = [&](const std::vector<std::string>& f, const PairChoice& p,
                               std::complex<double>& x) {
          double va, vb;
          if (f.size() <= std::max(p.col_a, p.col_b) ||
              !parse_number(f[p.col_a], va, layout->decimal_comma) ||
              !parse_number(f[p.col_b], vb, layout->decimal_comma))
            return false;
          va *= cols[p.col_a].scale;
          vb *= cols[p.col_b].scale;
          if (p.spec.a == Part::Re) {
            x = {va, vb};
          } else {
            const double m = p.spec.a == Part::Mag ? va : std::pow(10.0, va / 20.0);
            x = {m * std::cos(vb), m * std::sin(vb)};
          }
          return true;
        };
        std::vector<double> d;
        for (std::size_t i = first; i < lines.size(); ++i) {
          if (trim(lines[i].text).empty() || is_comment(lines[i].text)) continue;
          const auto f = row_fields(lines[i].text, *layout);
          std::complex<double> a, t;
          if (value(f, *s11, a) && value(f, pair, t)) d.push_back(std::abs(a + t - 1.0));
        }
        series_misfit = median_of(d);
      }
      char sm[32];
      std::snprintf(sm, sizeof sm, "%.3g", series_misfit);
      if (median >= 1e-3 && series_misfit > 0.1) {
        pair = *s11;
        s21_note += std::string("S11 and S21 are not those of one element in series between the "
                                "ports (median |S11 + S21 - 1| ") +
                    sm +
                    ", 0 for a series element: a filter, or a fixture with shunt paths), so "
                    "2*z0*(1 - S21)/S21 would not be the device's impedance: S11 read as the "
                    "input impedance of port 1 with port 2 terminated in z0";
      } else if (median < 1e-3 && s11 && s11->spec.quantity == Quantity::S) {
        pair = *s11;
        s21_note += std::string("S21 is at noise level (median |S21| ") + db +
                   " dB): nothing passes between the ports, so the device is taken to be on "
                   "port 1 and S11 is read as a reflection";
      } else {
        s21_note +=
            "transmission S21 read as a device in series between the two ports (series-through "
            "fixture): Z = 2*z0*(1 - S21)/S21, z0 = 50 ohm assumed; S21 is preferred to any "
            "S11 column, and never read as a reflection";
        if (median < 1e-3)
          s21_note += std::string(" (median |S21| ") + db + " dB: little passes)";
      }
    }
    if (lcr) {
      pair.col_a = lcr->col_a;
      pair.col_b = lcr->col_b;
      if (!lcr->pair.assumption.empty()) b.out.notes.push_back(lcr->pair.assumption);
      for (const auto col : {lcr->col_a, lcr->col_b}) {
        if (col == kNone) continue;
        if (cols[col].part == Part::Phase && cols[col].quantity == Quantity::Unknown)
          b.out.notes.push_back("the phase column does not say of what: read as the phase of Z");
        if (cols[col].part == Part::Phase && !cols[col].unit_given)
          b.out.notes.push_back("phase unit not given: degrees assumed");
      }
      b.out.magnitude_only = lcr->pair.magnitude_only;
    } else {
      if (pair.quantity_assumed)
        b.out.notes.push_back(
            "the columns do not say impedance, admittance or S11: read as impedance");
      if (pair.spec.quantity == Quantity::S)
        b.out.notes.push_back(
            "S11 without its reference impedance in the file: z0 = 50 ohm assumed");
      if (!s21_note.empty()) b.out.notes.push_back(s21_note);
      if (pair.spec.b == Part::Phase && !cols[pair.col_b].unit_given)
        b.out.notes.push_back("phase unit not given: degrees assumed");
    }
    if (!cols[fcol].unit_given) b.out.notes.push_back("frequency unit not given: Hz assumed");
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
      if (!used && !names[i].empty() && names[i] != "-")
        skipped.push_back(labels[i] + (cols[i].why.empty() ? "" : " (" + cols[i].why + ")"));
    }
    if (!skipped.empty()) b.out.notes.push_back("columns not read: " + list(skipped));
    b.out.notes.push_back("columns read: " + labels[fcol] + ", " + labels[pair.col_a] +
                          (pair.col_b == kNone ? std::string() : ", " + labels[pair.col_b]));
    if (smag != kNone)
      b.out.notes.push_back("uncertainty read (1 sigma): " + labels[smag] + ", " + labels[sphase] +
                            (kcol != kNone ? ", coverage factor " + labels[kcol] : std::string()));
  }
  b.out.quantity = lcr ? describe(lcr->pair) : describe(pair.spec);
  if (layout->joined_halves)
    b.out.notes.push_back("decimal commas with comma separators: each value was split in two");

  // Rows.
  bool comma_used = false;
  std::size_t empty_rows = 0;
  double coverage = std::nan("");
  bool coverage_varies = false;
  const auto number = [&](const std::vector<std::string>& f, std::size_t col, int line) {
    double v;
    if (!parse_number(f[col], v, layout->decimal_comma))
      fail(fn, name, line,
           "'" + f[col] + "' is not a number (column " +
               (names.empty() ? std::to_string(col + 1) : "'" + labels[col] + "'") + ")");
    if (layout->decimal_comma && f[col].find(',') != std::string::npos) comma_used = true;
    return v;
  };
  for (std::size_t i = first; i < lines.size(); ++i) {
    const auto& L = lines[i];
    if (trim(L.text).empty() || is_comment(L.text)) continue;
    auto f = row_fields(L.text, *layout);
    if (f.empty()) {  // ",,,,,,,,": a file padded with empty rows
      ++empty_rows;
      continue;
    }
    // Trailing columns left out (skipped ones, empty in the row: an instrument's "OFF").
    bool short_ok = given && f.size() < ncols;
    for (std::size_t k = f.size(); short_ok && k < ncols; ++k) short_ok = names[k] == "-";
    if (short_ok) f.resize(ncols);
    if (f.size() != ncols && !(names.empty() && f.size() >= 3))
      fail(fn, name, L.number,
           std::to_string(f.size()) + " columns, " +
               (names.empty() ? "the first row has"
                : given       ? opt.columns_origin + " names"
                              : "the header has") +
               " " + std::to_string(ncols));
    // Side-by-side sweeps of different lengths: the columns read are empty past theirs.
    if (fcol < f.size() && f[fcol].empty() && pair.col_a < f.size() && f[pair.col_a].empty() &&
        (pair.col_b == kNone || (pair.col_b < f.size() && f[pair.col_b].empty()))) {
      ++empty_rows;
      continue;
    }
    const double fhz = number(f, fcol, L.number) * cols[fcol].scale;
    const double a = number(f, pair.col_a, L.number) * cols[pair.col_a].scale;
    const double bv =
        pair.col_b == kNone ? 0.0 : number(f, pair.col_b, L.number) * cols[pair.col_b].scale;
    b.add(L.number, fhz,
          lcr ? lcr_impedance(lcr->pair, fhz, a, bv) : to_impedance(pair.spec, fhz, a, bv));
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
  if (empty_rows > 0)
    b.out.notes.push_back(std::to_string(empty_rows) +
                          " row(s) with empty fields in the columns read skipped");
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
