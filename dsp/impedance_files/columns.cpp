#include "dsp/impedance_files/columns.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <vector>

#include "dsp/impedance_files/text.hpp"

namespace piezo::dsp::zfiles {

namespace {

enum class UnitKind { Freq, Ohm, Siemens, Deg, Rad, Db, Henry, Farad, One };
struct Unit {
  UnitKind kind;
  double scale;
};

double si_prefix(std::string_view p, std::string_view allowed) {
  if (p.empty()) return 1.0;
  if (p.size() != 1 || allowed.find(p[0]) == std::string_view::npos) return 0.0;
  switch (p[0]) {
    case 'p':
      return 1e-12;
    case 'n':
      return 1e-9;
    case 'u':
      return 1e-6;
    case 'm':
      return 1e-3;
    case 'k':
    case 'K':
      return 1e3;
    case 'M':
      return 1e6;
    case 'G':
      return 1e9;
    case 'f':
      return 1e-15;
  }
  return 0.0;
}

std::optional<Unit> parse_unit(std::string_view raw) {
  const std::string_view u = trim(raw);
  const std::string l = lower(u);
  if (l.empty() || l == "u" || l == "1" || l == "-") return Unit{UnitKind::One, 1.0};
  if (l == "hz") return Unit{UnitKind::Freq, 1.0};
  if (l == "khz") return Unit{UnitKind::Freq, 1e3};
  if (l == "mhz") return Unit{UnitKind::Freq, 1e6};  // "mHz" too: nobody sweeps in millihertz
  if (l == "ghz") return Unit{UnitKind::Freq, 1e9};
  if (l == "deg" || l == "degree" || l == "degrees")
    return Unit{UnitKind::Deg, std::numbers::pi / 180};
  if (l == "rad" || l == "radian" || l == "radians") return Unit{UnitKind::Rad, 1.0};
  if (l == "db") return Unit{UnitKind::Db, 1.0};
  if (l == "siemens" || l == "mho" || l == "mhos") return Unit{UnitKind::Siemens, 1.0};
  for (std::string_view word : {"ohms", "ohm"}) {
    if (l.size() >= word.size() && l.compare(l.size() - word.size(), word.size(), word) == 0) {
      const double s = si_prefix(u.substr(0, u.size() - word.size()), "umkKMG");
      if (s > 0) return Unit{UnitKind::Ohm, s};
    }
  }
  if (u.back() == 'S' || u.back() == 'H' || u.back() == 'F') {
    const double s = si_prefix(u.substr(0, u.size() - 1), u.back() == 'F' ? "fpnum" : "pnumk");
    const UnitKind k = u.back() == 'S'   ? UnitKind::Siemens
                       : u.back() == 'H' ? UnitKind::Henry
                                         : UnitKind::Farad;
    if (s > 0) return Unit{k, s};
  }
  return std::nullopt;
}

// UTF-8 (and stray Latin-1) symbols to ASCII words: Ω Ω -> Ohm, ° -> deg,
// θ -> theta, φ -> phi, δ -> delta, µ μ -> u.
std::string ascii_symbols(std::string_view s) {
  static constexpr std::array<std::pair<std::string_view, std::string_view>, 9> kMap{{
      {"\xCE\xA9", "Ohm"},
      {"\xE2\x84\xA6", "Ohm"},
      {"\xC2\xB0", "deg"},
      {"\xCE\xB8", "theta"},
      {"\xCF\x86", "phi"},
      {"\xCF\x95", "phi"},
      {"\xCE\xB4", "delta"},
      {"\xC2\xB5", "u"},
      {"\xCE\xBC", "u"},
  }};
  std::string out;
  for (std::size_t i = 0; i < s.size();) {
    bool hit = false;
    for (const auto& [from, to] : kMap) {
      if (s.substr(i, from.size()) == from) {
        out += to;
        i += from.size();
        hit = true;
        break;
      }
    }
    if (hit) continue;
    const auto c = static_cast<unsigned char>(s[i]);
    const bool after_ascii = i == 0 || static_cast<unsigned char>(s[i - 1]) < 0x80;
    if (c == 0xB0 && after_ascii)
      out += "deg";  // Latin-1 degree sign
    else if (c == 0xB5 && after_ascii)
      out += "u";  // Latin-1 micro sign
    else
      out += s[i];
    ++i;
  }
  return out;
}

bool in(std::string_view w, std::initializer_list<std::string_view> set) {
  return std::find(set.begin(), set.end(), w) != set.end();
}

std::optional<Quantity> quantity_word(std::string_view w) {
  if (in(w, {"z", "impedance", "imp", "zin", "z11", "zx"})) return Quantity::Z;
  if (in(w, {"y", "admittance", "adm", "y11"})) return Quantity::Y;
  if (in(w, {"s11", "s", "gamma", "reflection", "refl", "rho"})) return Quantity::S;
  if (w == "s21") return Quantity::S21;
  return std::nullopt;
}

// A part word, with the quantity it fixes (R, X: impedance; G, B: admittance).
std::optional<std::pair<Part, Quantity>> part_word(std::string_view w) {
  using P = std::pair<Part, Quantity>;
  const auto U = Quantity::Unknown;
  if (in(w,
         {"mag", "magnitude", "abs", "absolute", "amplitude", "ampl", "modulus", "mod", "linmag"}))
    return P{Part::Mag, U};
  if (in(w, {"db", "logmag", "dbmag"})) return P{Part::MagDb, U};
  if (in(w, {"phase", "phi", "theta", "angle", "ang", "arg", "pha", "ph"}))
    return P{Part::Phase, U};
  if (in(w, {"re", "real"})) return P{Part::Re, U};
  if (in(w, {"im", "imag", "imaginary"})) return P{Part::Im, U};
  if (in(w, {"r", "resistance", "rs", "esr"})) return P{Part::Re, Quantity::Z};
  if (in(w, {"x", "reactance", "xs"})) return P{Part::Im, Quantity::Z};
  if (in(w, {"g", "conductance", "gp"})) return P{Part::Re, Quantity::Y};
  if (in(w, {"b", "susceptance"})) return P{Part::Im, Quantity::Y};
  if (w == "ls") return P{Part::Ls, Quantity::Z};
  if (w == "cs") return P{Part::Cs, Quantity::Z};
  if (w == "lp") return P{Part::Lp, Quantity::Y};
  if (w == "cp") return P{Part::Cp, Quantity::Y};
  if (w == "rp") return P{Part::Rp, Quantity::Y};
  if (in(w, {"d", "df", "dissipation", "tan", "tand"})) return P{Part::D, U};
  if (in(w, {"q", "quality"})) return P{Part::Q, U};
  return std::nullopt;
}

bool not_impedance_word(std::string_view w) {
  return in(w, {"gain",        "transmission", "s12",   "s22", "voltage", "current",
                "vac",         "iac",          "vdc",  "idc",   "dcv", "dci",     "power",
                "temperature", "temp",         "time", "delay", "gd",  "vswr",    "swr",
                "return",      "loss",         "a1",   "a2",    "b1",  "b2",      "t"});
}

}  // namespace

ColumnMeaning classify_column(std::string_view header) {
  ColumnMeaning m;
  const auto ignored = [&m](const char* why) {
    m.role = Role::Ignored;
    m.why = why;
    return m;
  };
  std::string s = ascii_symbols(trim(header));
  // "Eq=(1-S11)/(1+S11)(DB)": a VNA's equation trace, not the parameter it names.
  if (s.find('=') != std::string::npos) return ignored("an equation of other traces");

  // Units in brackets; groups that are not units stay as words ("S11(REAL)").
  std::optional<Unit> unit;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (s[i] != '(' && s[i] != '[') continue;
    const char close = s[i] == '(' ? ')' : ']';
    const auto j = s.find(close, i + 1);
    if (j == std::string::npos) break;
    if (auto u = parse_unit(std::string_view(s).substr(i + 1, j - i - 1))) {
      unit = u;
      s.replace(i, j - i + 1, std::string(j - i + 1, ' '));
    } else {
      s[i] = ' ';
      s[j] = ' ';
    }
    i = j;
  }
  // "Frequency / Hz", "|Z| / kOhm"
  if (const auto slash = s.rfind('/'); !unit && slash != std::string::npos) {
    if (auto u = parse_unit(std::string_view(s).substr(slash + 1)); u && u->kind != UnitKind::One) {
      unit = u;
      s.resize(slash);
    }
  }
  // Words, case kept for a trailing unit ("f_hz", "re_ohm", "Z_kOhm", "phase_sigma_deg").
  std::vector<std::string> words;
  std::string cur;
  for (char c : s + ' ') {
    if (std::isalnum(static_cast<unsigned char>(c)) || c == '|') {
      cur += c;
    } else if (!cur.empty()) {
      words.push_back(cur);
      cur.clear();
    }
  }
  if (!unit && words.size() >= 2) {
    if (auto u = parse_unit(words.back()); u && u->kind != UnitKind::One) {
      unit = u;
      words.pop_back();
    }
  }
  m.unit_given = unit.has_value();

  bool freq = false, memory = false, sigma = false, coverage = false, other = false, bars = false,
       log = false;
  std::vector<Quantity> qs;
  std::vector<std::pair<Part, Quantity>> parts;
  const auto take = [&](const std::string& w) {
    if (auto q = quantity_word(w)) {
      qs.push_back(*q);
      return true;
    }
    if (auto p = part_word(w)) {
      parts.push_back(*p);
      return true;
    }
    return false;
  };
  // "Transmission Loss(dB)" (vna/J's transmission mode): S21 in dB.
  bool transmission = false;
  for (const auto& w : words) transmission = transmission || lower(w) == "transmission";
  for (auto w : words) {
    if (transmission && in(lower(w), {"transmission", "loss"})) {
      if (lower(w) == "transmission")
        qs.push_back(Quantity::S21);
      else
        m.loss = true;
      continue;
    }
    if (w.find('|') != std::string::npos) {
      bars = true;
      w.erase(std::remove(w.begin(), w.end(), '|'), w.end());
    }
    w = lower(w);
    if (w.empty() || std::all_of(w.begin(), w.end(), [](char c) {
          return std::isdigit(static_cast<unsigned char>(c));
        }))
      continue;
    if (in(w, {"f", "freq", "frequency", "frequencies", "stimulus"}))
      freq = true;
    else if (in(w, {"mem", "memory"}))
      memory = true;
    else if (in(w, {"sigma", "std", "stdev", "stddev", "uncertainty", "unc"}))
      sigma = true;
    else if (w == "coverage")
      coverage = true;
    else if (w == "log")
      log = true;
    else if (not_impedance_word(w))
      other = true;
    else if (!take(w) && w.size() <= 16) {
      // "zmag", "magz", "rez", "zphase", "thetaz", ...
      for (std::size_t k = 1; k < w.size(); ++k) {
        const std::string a = w.substr(0, k), b = w.substr(k);
        if ((quantity_word(a) && part_word(b)) || (part_word(a) && quantity_word(b))) {
          take(a);
          take(b);
          break;
        }
      }
    }
  }

  if (memory) return ignored("memory trace");
  if (other) return ignored("not an impedance quantity");
  if (coverage) {
    m.role = Role::Coverage;
    return m;
  }

  const UnitKind uk = unit ? unit->kind : UnitKind::One;
  const double us = unit ? unit->scale : 1.0;
  if (freq && parts.empty() && qs.empty()) {
    if (unit && uk != UnitKind::Freq) return ignored("frequency with a unit that is not one");
    m.role = Role::Frequency;
    m.scale = us;
    return m;
  }

  // One part, one quantity at most, and they must agree.
  Part part = Part::None;
  Quantity q = Quantity::Unknown;
  for (const auto& [p, pq] : parts) {
    if (part != Part::None && part != p) return ignored("names more than one component");
    part = p;
    if (pq != Quantity::Unknown) q = pq;
  }
  for (const auto wq : qs) {
    if (q != Quantity::Unknown && q != wq) return ignored("names two quantities");
    q = wq;
  }
  if (part == Part::None && bars && q != Quantity::Unknown) part = Part::Mag;  // |Z|, |Y|
  if (part == Part::Mag && (log || uk == UnitKind::Db)) part = Part::MagDb;
  if (part == Part::None) {
    if (uk == UnitKind::Deg || uk == UnitKind::Rad)
      part = Part::Phase;
    else if (uk == UnitKind::Db)
      part = Part::MagDb;
    else if (q == Quantity::Z || q == Quantity::Y)
      part = Part::Mag;  // "Impedance (Ω)", "Z"
  }
  if (q == Quantity::Unknown && (part == Part::Mag || part == Part::Re || part == Part::Im)) {
    if (uk == UnitKind::Ohm) q = Quantity::Z;
    if (uk == UnitKind::Siemens) q = Quantity::Y;
  }
  if (part == Part::None) return ignored("not a component we know");

  // The unit must fit the part.
  bool fits = false;
  switch (part) {
    case Part::Phase:
      fits = !unit || uk == UnitKind::Deg || uk == UnitKind::Rad;
      break;
    case Part::MagDb:
      fits = !unit || uk == UnitKind::Db;
      break;
    case Part::Mag:
    case Part::Re:
    case Part::Im:
      fits = !unit || uk == UnitKind::One ||
             (uk == UnitKind::Ohm && q != Quantity::Y && q != Quantity::S && q != Quantity::S21) ||
             (uk == UnitKind::Siemens && q != Quantity::Z && q != Quantity::S &&
              q != Quantity::S21);
      break;
    case Part::Rp:
      fits = !unit || uk == UnitKind::Ohm;
      break;
    case Part::Ls:
    case Part::Lp:
      fits = !unit || uk == UnitKind::Henry;
      break;
    case Part::Cs:
    case Part::Cp:
      fits = !unit || uk == UnitKind::Farad;
      break;
    case Part::D:
    case Part::Q:
      fits = !unit || uk == UnitKind::One;
      break;
    case Part::None:
      break;
  }
  if (!fits) return ignored("its unit does not fit its name");

  m.part = part;
  m.quantity = q;
  m.scale = part == Part::Phase ? (uk == UnitKind::Rad ? 1.0 : std::numbers::pi / 180) : us;
  if (sigma) {
    if (part == Part::Mag)
      m.role = Role::SigmaMag;
    else if (part == Part::Phase)
      m.role = Role::SigmaPhase;
    else
      return ignored("uncertainty of a component we do not carry");
    return m;
  }
  m.role = Role::Value;
  return m;
}

std::vector<std::string> parse_column_spec(std::string_view spec) {
  std::vector<std::string> out;
  bool has_f = false;
  std::size_t start = 0;
  for (std::size_t i = 0; i <= spec.size(); ++i) {
    if (i < spec.size() && spec[i] != ',') continue;
    const std::string item(trim(spec.substr(start, i - start)));
    start = i + 1;
    if (item == "-" || lower(item) == "skip") {
      out.push_back("-");
      continue;
    }
    // "-theta(deg)": the column negated (a current's phase for the impedance's).
    const bool negated = item.size() > 1 && item.front() == '-';
    const auto m = classify_column(negated ? std::string_view(item).substr(1) : item);
    if (item.empty() || m.role == Role::Ignored)
      throw std::invalid_argument(
          "--columns: '" + printable(item) + "' is not a column we know" +
          (m.why.empty() ? std::string() : " (" + m.why + ")") +
          "; use f, R, X, G, B, |Z|, |Y|, theta, Rs, Rp, Cs, Cp, Ls, Lp, D, Q, re, im, S11, S21 "
          "with a unit in brackets (f[kHz], G[uS], theta[deg], |Z|[kohm]), a leading - to negate "
          "one (-theta[deg]), or - alone to skip a column");
    has_f = has_f || m.role == Role::Frequency;
    out.push_back(item);
  }
  if (!has_f)
    throw std::invalid_argument("--columns: no frequency among '" + printable(spec) +
                                "' (e.g. --columns f[Hz],R[ohm],X[ohm])");
  return out;
}

}  // namespace piezo::dsp::zfiles
