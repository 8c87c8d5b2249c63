// dsp/impedance_files, issue 39 item 2: the layouts labs save. HIOKI IM3570
// CSV (Shift-JIS units, quoted fields, every parameter pair, OFF), LabOne
// exports (';' CSV with chunk/timestamp columns, '%' text, param0/param1),
// transmission exports (two-port Touchstone, S21 columns, vna/J), units in
// headers, --columns for a headerless table, repeated frequencies, and
// messages that name the file and the next step but no function. Every input
// is written here from an analytic BVD impedance (the truth is known).
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <cstdarg>
#include <cstdio>
#include <functional>
#include <numbers>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "bvd_model.hpp"
#include "dsp/impedance_files/lcr_parameters.hpp"
#include "dsp/impedance_files/read_any.hpp"

namespace {

using namespace piezo;
using dsp::ImpedanceFileFormat;
using cd = std::complex<double>;
constexpr double kDeg = 180.0 / std::numbers::pi;
constexpr double kTwoPi = 2.0 * std::numbers::pi;

std::string fmt(const char* f, ...) __attribute__((format(printf, 1, 2)));
std::string fmt(const char* f, ...) {
  char buf[512];
  va_list ap;
  va_start(ap, f);
  std::vsnprintf(buf, sizeof buf, f, ap);
  va_end(ap);
  return buf;
}

// HIOKI's engineering notation, mantissa 1 ... 999.9: "982.8809E+00", here with 10 decimals.
std::string eng(double v) {
  if (v == 0) return "0.0000000000E+00";
  int e = static_cast<int>(std::floor(std::log10(std::abs(v)) / 3.0)) * 3;
  return fmt("%.10fE%+03d", v / std::pow(10.0, e), e);
}

// One BVD mode, fr 50 kHz, fa 52 kHz, C0 2.5 nF, ζ 0.005 (as test_impedance_files.cpp).
struct Truth {
  std::vector<double> f;
  std::vector<cd> z;
};
Truth truth(int n = 41) {
  const auto m = bvd::make_bvd({50e3}, {52e3}, 2.5e-9, {0.005});
  Truth t;
  for (int k = 0; k < n; ++k) {
    t.f.push_back(40e3 + 20e3 * k / (n - 1));
    t.z.push_back(m.impedance_at(t.f.back()));
  }
  return t;
}

dsp::ImportedImpedance read(const std::string& text, const std::string& name = "x.csv",
                            const std::string& columns = "") {
  std::istringstream in(text);
  dsp::ImpedanceReadOptions o;
  o.columns = columns;
  return dsp::read_impedance_any(in, name, o);
}

void expect_curve(const dsp::ImportedImpedance& c, const Truth& t, double rel,
                  const std::string& what) {
  ASSERT_EQ(c.size(), t.f.size()) << what;
  for (std::size_t k = 0; k < t.f.size(); ++k) {
    EXPECT_NEAR(c.f_hz[k] / t.f[k], 1.0, 1e-9) << what << " point " << k;
    EXPECT_LE(std::abs(c.z_ohm[k] - t.z[k]), rel * std::abs(t.z[k]))
        << what << " point " << k << ": " << c.z_ohm[k] << " vs " << t.z[k];
  }
}

bool has_note(const dsp::ImportedImpedance& c, const std::string& part) {
  for (const auto& n : c.notes)
    if (n.find(part) != std::string::npos) return true;
  return false;
}

std::string error_of(const std::string& text, const std::string& name = "x.csv",
                     const std::string& columns = "") {
  try {
    read(text, name, columns);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  ADD_FAILURE() << "no error for:\n" << text;
  return "";
}

// Every byte of s is valid UTF-8 (notes and messages go into JSON).
bool utf8(const std::string& s) {
  for (std::size_t i = 0; i < s.size();) {
    const auto c = static_cast<unsigned char>(s[i]);
    const std::size_t n = c < 0x80 ? 1 : (c >> 5) == 6 ? 2 : (c >> 4) == 14 ? 3 : (c >> 3) == 30 ? 4 : 0;
    if (n == 0 || i + n > s.size()) return false;
    for (std::size_t k = 1; k < n; ++k)
      if ((static_cast<unsigned char>(s[i + k]) & 0xC0) != 0x80) return false;
    i += n;
  }
  return true;
}

// ------------------------------------------------------------------ parameter pairs

// Each instrument parameter of one Z, at frequency f.
double param(const std::string& p, double f, cd z) {
  const double w = kTwoPi * f;
  const cd y = 1.0 / z;
  if (p == "Z") return std::abs(z);
  if (p == "Y") return std::abs(y);
  if (p == "theta") return std::arg(z);
  if (p == "Rs") return z.real();
  if (p == "X") return z.imag();
  if (p == "G") return y.real();
  if (p == "B") return y.imag();
  if (p == "Rp") return 1.0 / y.real();
  if (p == "Cs") return -1.0 / (w * z.imag());
  if (p == "Ls") return z.imag() / w;
  if (p == "Cp") return y.imag() / w;
  if (p == "Lp") return -1.0 / (w * y.imag());
  if (p == "D") return z.real() / std::abs(z.imag());
  if (p == "Q") return std::abs(z.imag()) / z.real();
  return NAN;
}

// Every pair the solver calls complex gives Z back, on a capacitive and an
// inductive point; the |Z|-only pairs give |Z|; the others are refused.
TEST(LcrParameters, EveryPairGivesZOrSaysWhy) {
  namespace zf = piezo::dsp::zfiles;
  using L = zf::Lcr;
  const std::vector<std::pair<L, std::string>> all = {
      {L::AbsZ, "Z"}, {L::AbsY, "Y"}, {L::Phase, "theta"}, {L::R, "Rs"}, {L::X, "X"},
      {L::G, "G"},    {L::B, "B"},    {L::Rp, "Rp"},       {L::Cs, "Cs"}, {L::Cp, "Cp"},
      {L::Ls, "Ls"},  {L::Lp, "Lp"},  {L::D, "D"},         {L::Q, "Q"}};
  int complex = 0, magnitude = 0, none = 0;
  for (const cd z : {cd(120.0, -830.0), cd(45.0, 310.0)}) {
    const double f = 51e3;
    for (std::size_t i = 0; i < all.size(); ++i) {
      for (std::size_t j = 0; j < all.size(); ++j) {
        if (i == j) continue;
        const auto p = zf::lcr_pair(all[i].first, all[j].first);
        const double a = param(all[i].second, f, z), b = param(all[j].second, f, z);
        if (!p) {
          ++none;
          continue;
        }
        const cd got = zf::lcr_impedance(*p, f, a, b);
        const std::string what = all[i].second + "-" + all[j].second;
        if (p->magnitude_only) {
          ++magnitude;
          EXPECT_NEAR(got.real(), std::abs(z), 1e-9 * std::abs(z)) << what;
          EXPECT_EQ(got.imag(), 0.0) << what;
          continue;
        }
        ++complex;
        // Pairs that know only R² (|Z| X, |Y| B, X B) assume R >= 0: true here.
        EXPECT_LE(std::abs(got - z), 1e-9 * std::abs(z)) << what << ": " << got << " vs " << z;
      }
    }
  }
  EXPECT_GT(complex, 100);
  EXPECT_GT(magnitude, 10);
  EXPECT_GT(none, 10);
  // |Z| alone: magnitude only; anything else alone: nothing.
  ASSERT_TRUE(zf::lcr_pair(L::AbsZ, std::nullopt));
  EXPECT_TRUE(zf::lcr_pair(L::AbsZ, std::nullopt)->magnitude_only);
  EXPECT_FALSE(zf::lcr_pair(L::G, std::nullopt));
  EXPECT_FALSE(zf::lcr_pair(L::Phase, std::nullopt));
  EXPECT_FALSE(zf::lcr_pair(L::Phase, L::D));
  EXPECT_FALSE(zf::lcr_pair(L::Cs, L::X));  // one kind twice
  // |X| a rounding above |Z|: R = 0, not NaN.
  const auto zx = zf::lcr_pair(L::AbsZ, L::X);
  EXPECT_EQ(zf::lcr_impedance(*zx, 1e3, 10.0, -10.0000001), cd(0, -10.0000001));
}

// ------------------------------------------------------------------ HIOKI

// A HIOKI IM3570 sweep as the instrument saves it: quoted settings, quoted
// fields, CR LF, Shift-JIS units, engineering numbers.
std::string hioki(const Truth& t, const std::string& p1, const std::string& u1,
                  const std::string& p2, const std::string& u2) {
  std::string s =
      "\"MODEL\",\"IM3570\"\r\n\"VERSION\",\"V2.10\"\r\n\"DATE\",\"2024/05/12\"\r\n"
      "\"TIME\",\"10:12:33\"\r\n\"MODE\",\"ANALYZER\"\r\n\"SWEEP\",\"FREQ\"\r\n"
      "\"\x91\xaa\x92\xe8\x83\x82\x81\x5b\x83\x68\",\"LCR\"\r\n";  // a Japanese key in Shift-JIS
  s += "\"No.\",\"FREQUENCY(Hz)\",\"" + p1 + (u1.empty() ? "" : "[" + u1 + "]") + "\",\"" + p2 +
       (u2.empty() || p2 == "OFF" ? "" : "[" + u2 + "]") + "\"\r\n";
  for (std::size_t k = 0; k < t.f.size(); ++k) {
    const auto value = [&](const std::string& p) {
      if (p == "OFF") return std::string();
      const std::string name = p == "\x83\xc6" ? "theta" : p;
      double v = param(name, t.f[k], t.z[k]);
      if (std::isnan(v)) v = 1.0;  // Rdc
      if (name == "theta") v *= kDeg;
      return eng(v);
    };
    s += fmt("\"%zu\",\"%s\",\"%s\",\"%s\"\r\n", k + 1, eng(t.f[k]).c_str(), value(p1).c_str(),
             value(p2).c_str());
  }
  return s;
}

const std::string kOhmSjis = "\x83\xb6";
const std::string kThetaSjis = "\x83\xc6";
const std::string kDegSjis = "\x81\x8b";

TEST(Hioki, Im3570CsvEveryParameterPair) {
  const auto t = truth(21);
  // The header: |Z| and X, Ω in Shift-JIS.
  const std::string zx = hioki(t, "Z", kOhmSjis, "X", kOhmSjis);
  EXPECT_EQ(dsp::detect_impedance_format(zx, "im.csv"), ImpedanceFileFormat::Hioki);
  const auto c = read(zx, "im.csv");
  EXPECT_EQ(c.format, ImpedanceFileFormat::Hioki);
  EXPECT_EQ(c.format_name, "HIOKI IM3570 CSV");
  EXPECT_FALSE(c.magnitude_only);
  expect_curve(c, t, 1e-8, "HIOKI Z-X");
  EXPECT_TRUE(has_note(c, "R = sqrt(|Z|^2 - X^2) >= 0 assumed"));
  EXPECT_TRUE(has_note(c, "Z[\xCE\xA9]"));  // the column named in UTF-8 in the notes
  for (const auto& n : c.notes) EXPECT_TRUE(utf8(n)) << n;

  struct Pair {
    std::string p1, u1, p2, u2;
  };
  const std::vector<Pair> pairs = {
      {"Z", kOhmSjis, kThetaSjis, "deg"}, {"Z", kOhmSjis, kThetaSjis, kDegSjis},
      {"Rs", kOhmSjis, "X", kOhmSjis},    {"G", "S", "B", "S"},
      {"Y", "S", kThetaSjis, "deg"},      {"Cs", "F", "D", ""},
      {"Cs", "F", "Rs", kOhmSjis},        {"Cp", "F", "D", ""},
      {"Cp", "F", "Rp", kOhmSjis},        {"Ls", "H", "Rs", kOhmSjis},
      {"Lp", "H", "Rp", kOhmSjis},        {"Cp", "F", "G", "S"},
      {"Ls", "H", "Q", ""},               {"Z", "\xEA\x9F", "B", "S"},  // any non-ASCII Ω
      {"X", kOhmSjis, "D", ""},           {"Rs", kOhmSjis, kThetaSjis, "deg"},
  };
  for (const auto& p : pairs) {
    const std::string what = "HIOKI " + p.p1 + "-" + p.p2;
    const auto r = read(hioki(t, p.p1, p.u1, p.p2, p.u2), "im.csv");
    EXPECT_FALSE(r.magnitude_only) << what;
    expect_curve(r, t, 1e-8, what);
  }
  // θ is the phase of Z, said in a note.
  EXPECT_TRUE(has_note(read(hioki(t, "Z", kOhmSjis, kThetaSjis, "deg"), "im.csv"),
                       "theta read as the phase of Z"));
}

TEST(Hioki, OneParameterOffGivesMagnitudeOrARefusal) {
  const auto t = truth(11);
  // |Z| alone: magnitude only.
  const auto m = read(hioki(t, "Z", kOhmSjis, "OFF", ""), "im.csv");
  EXPECT_TRUE(m.magnitude_only);
  ASSERT_EQ(m.size(), t.f.size());
  for (std::size_t k = 0; k < t.f.size(); ++k) {
    EXPECT_NEAR(m.z_ohm[k].real() / std::abs(t.z[k]), 1.0, 1e-9);
    EXPECT_EQ(m.z_ohm[k].imag(), 0.0);
  }
  EXPECT_TRUE(has_note(m, "read as |Z| alone"));
  // |Z| and R: the sign of X is missing: magnitude only, said.
  const auto zr = read(hioki(t, "Z", kOhmSjis, "Rs", kOhmSjis), "im.csv");
  EXPECT_TRUE(zr.magnitude_only);
  EXPECT_TRUE(has_note(zr, "do not give the sign of the reactance"));
  // G alone, θ alone, θ with D: refused, naming the file and what is missing.
  for (const auto& [p1, u1, p2] :
       std::vector<std::tuple<std::string, std::string, std::string>>{
           {"G", "S", "OFF"}, {kThetaSjis, "deg", "OFF"}, {kThetaSjis, "deg", "D"}}) {
    const std::string e = error_of(hioki(t, p1, u1, p2, ""), "lab/im3570.csv");
    EXPECT_EQ(e.rfind("lab/im3570.csv: line ", 0), 0u) << e;
    EXPECT_NE(e.find("neither complex Z nor |Z|"), std::string::npos) << e;
    EXPECT_NE(e.find("a second parameter is needed"), std::string::npos) << e;
    EXPECT_EQ(e.find("read_"), std::string::npos) << e;
    EXPECT_TRUE(utf8(e)) << e;
  }
  // Rdc is not an impedance: named in a note, and alone refused.
  const std::string rdc = error_of(hioki(t, "Rdc", kOhmSjis, "OFF", ""), "im.csv");
  EXPECT_NE(rdc.find("no impedance columns"), std::string::npos) << rdc;
}

// ------------------------------------------------------------------ LabOne

std::string labone_csv(const Truth& t, int chunks = 1) {
  std::string s = "chunk;timestamp;grid;frequency;realz;imagz;absz;phasez;param0;param1\n";
  for (int c = 0; c < chunks; ++c)
    for (std::size_t k = 0; k < t.f.size(); ++k) {
      const cd z = t.z[k] * (c + 1 == chunks ? 1.0 : 2.0);  // earlier sweeps differ
      s += fmt("%d;%llu;%.15g;%.15g;%.15g;%.15g;%.15g;%.15g;%.15g;%.15g\n", c,
               123456789012ULL + 1000 * k, t.f[k], t.f[k], z.real(), z.imag(), std::abs(z),
               std::arg(z), 1e-9, 0.01);
    }
  return s;
}

TEST(LabOne, SweeperCsvTextAndParameters) {
  const auto t = truth(21);
  const std::string csv = labone_csv(t);
  EXPECT_EQ(dsp::detect_impedance_format(csv, "dev3120_imps_0_sample_00000.csv"),
            ImpedanceFileFormat::LabOne);
  const auto c = read(csv, "dev3120_imps_0_sample_00000.csv");
  EXPECT_EQ(c.format, ImpedanceFileFormat::LabOne);
  expect_curve(c, t, 1e-13, "LabOne realz/imagz");

  // Several sweeps: the last read, said.
  const auto multi = read(labone_csv(t, 3), "l.csv");
  expect_curve(multi, t, 1e-13, "LabOne last chunk");
  EXPECT_TRUE(has_note(multi, "3 sweeps in the file"));

  // absz/phasez (radians) in a '%' text export; a point not measured (nan).
  std::string txt = "% Zurich Instruments LabOne 23.06 sweeper export\n% device dev5123\n"
                    "% frequency absz phasez\n";
  for (std::size_t k = 0; k < t.f.size(); ++k)
    txt += fmt("%.15g %.15g %.15g\n", t.f[k], std::abs(t.z[k]), std::arg(t.z[k]));
  txt += fmt("%.15g nan nan\n", 61e3);
  EXPECT_EQ(dsp::detect_impedance_format(txt, "sweep.txt"), ImpedanceFileFormat::LabOne);
  const auto p = read(txt, "sweep.txt");
  expect_curve(p, t, 1e-13, "LabOne absz/phasez");
  EXPECT_TRUE(has_note(p, "phasez read in radians"));
  EXPECT_TRUE(has_note(p, "1 point(s) without a value (nan) left out"));

  // LabOne's native (transposed) sweeper CSV: one row per chunk and field, the header
  // padded with ';', frequencies descending, an unfinished last sweep (nan): the last
  // complete sweep read.
  {
    std::string tr = "chunk;timestamp;size;fieldname" + std::string(t.f.size(), ';') + "\n";
    const auto row = [&](int chunk, const char* field, const std::function<double(std::size_t)>& v,
                         bool nan_tail) {
      std::string r = fmt("%d;%d;%zu;%s", chunk, 1000 + chunk, t.f.size(), field);
      for (std::size_t k = t.f.size(); k-- > 0;)  // descending
        r += nan_tail && k < 3 ? std::string(";nan") : fmt(";%.15g", v(k));
      return r + "\n";
    };
    for (int chunk = 0; chunk < 3; ++chunk) {
      const double scale = chunk == 1 ? 1.0 : 3.0;  // chunk 1 is the last complete sweep
      const bool unfinished = chunk == 2;
      tr += row(chunk, "absz", [&](std::size_t k) { return scale * std::abs(t.z[k]); }, unfinished);
      tr += row(chunk, "frequency", [&](std::size_t k) { return t.f[k]; }, unfinished);
      tr += row(chunk, "imagz", [&](std::size_t k) { return scale * t.z[k].imag(); }, unfinished);
      tr += row(chunk, "realz", [&](std::size_t k) { return scale * t.z[k].real(); }, unfinished);
    }
    EXPECT_EQ(dsp::detect_impedance_format(tr, "dev3221_imps_0_sample_00000.csv"),
              ImpedanceFileFormat::LabOne);
    const auto n = read(tr, "dev3221_imps_0_sample_00000.csv");
    expect_curve(n, t, 1e-13, "LabOne transposed");
    EXPECT_TRUE(has_note(n, "transposed layout (one row per field): chunk 1 read, 3 chunk(s)"));
    EXPECT_TRUE(has_note(n, "descending sweep: reversed"));
  }

  // param0/param1 with the representation stated: Cp and D.
  std::string rep = "% representation: Cp D\nfrequency;param0;param1\n";
  for (std::size_t k = 0; k < t.f.size(); ++k)
    rep += fmt("%.15g;%.15g;%.15g\n", t.f[k], param("Cp", t.f[k], t.z[k]),
               param("D", t.f[k], t.z[k]));
  expect_curve(read(rep, "rep.csv"), t, 1e-12, "LabOne param0/param1 Cp D");
  // ... and without it: refused with the next step.
  std::string norep = "frequency;param0;param1\n1000;1e-9;0.01\n";
  EXPECT_NE(error_of(norep, "n.csv").find("without a line stating their representation"),
            std::string::npos);
  // A demodulator sweep: volts, not an impedance.
  const std::string demod =
      error_of("chunk;timestamp;grid;frequency;x;y;r;phase\n0;1;1000;1000;0.1;0.2;0.22;1.1\n",
               "demod.csv");
  EXPECT_NE(demod.find("demodulator signals"), std::string::npos) << demod;
  EXPECT_EQ(demod.rfind("demod.csv: line 1: ", 0), 0u) << demod;
}

// ------------------------------------------------------------------ units, separators

TEST(Table, UnitsDecimalCommasAndBom) {
  const auto t = truth(11);
  const auto write = [&](const std::string& header, const std::string& sep,
                         const std::function<std::string(std::size_t)>& row) {
    std::string s = header + "\n";
    for (std::size_t k = 0; k < t.f.size(); ++k) s += row(k) + "\n";
    (void)sep;
    return s;
  };
  // MHz and µS (UTF-8 µ), uS, Latin-1 µ, mS, kΩ, radians.
  expect_curve(read(write("Frequency [MHz];G [\xC2\xB5S];B [uS]", ";",
                          [&](std::size_t k) {
                            const cd y = 1.0 / t.z[k];
                            return fmt("%.15g;%.15g;%.15g", t.f[k] / 1e6, y.real() * 1e6,
                                       y.imag() * 1e6);
                          })),
               t, 1e-13, "MHz, uS");
  expect_curve(read(write("f (kHz)\tG (\xB5S)\tB (mS)", "\t",
                          [&](std::size_t k) {
                            const cd y = 1.0 / t.z[k];
                            return fmt("%.15g\t%.15g\t%.15g", t.f[k] / 1e3, y.real() * 1e6,
                                       y.imag() * 1e3);
                          })),
               t, 1e-13, "kHz, Latin-1 uS, mS");
  expect_curve(read(write("freq/kHz,|Z|/kohm,phase/rad", ",",
                          [&](std::size_t k) {
                            return fmt("%.15g,%.15g,%.15g", t.f[k] / 1e3, std::abs(t.z[k]) / 1e3,
                                       std::arg(t.z[k]));
                          })),
               t, 1e-13, "kohm, rad");
  // Semicolons, decimal commas, a UTF-8 BOM, CR LF, degrees.
  std::string s = "\xEF\xBB\xBF" "Frequenz (Hz);|Z| (Ohm);Phase (deg)\r\n";
  for (std::size_t k = 0; k < t.f.size(); ++k) {
    std::string row =
        fmt("%.12g;%.12g;%.12g\r\n", t.f[k], std::abs(t.z[k]), std::arg(t.z[k]) * kDeg);
    for (auto& ch : row) ch = ch == '.' ? ',' : ch;
    s += row;
  }
  // "Frequenz" is no word we know: refused, the message says how to name the columns.
  const std::string e = error_of(s, "de.csv");
  EXPECT_NE(e.find("no frequency column"), std::string::npos) << e;
  EXPECT_NE(e.find("--columns"), std::string::npos) << e;
  const auto d = read(s, "de.csv", "f[Hz],|Z|[ohm],phase[deg]");
  expect_curve(d, t, 3e-11, "decimal commas, BOM, --columns");
  EXPECT_TRUE(has_note(d, "decimal commas"));
  s.replace(s.find("Frequenz"), 8, "Frequency");
  expect_curve(read(s, "de.csv"), t, 3e-11, "decimal commas, BOM");
}

// ------------------------------------------------------------------ transmission

// S-parameters of Z in series between two z0 ports: S11 = S22 = Z/(Z + 2z0), S21 = S12 = 2z0/(Z + 2z0).
cd s21_of(cd z, double z0 = 50) { return 2 * z0 / (z + 2 * z0); }
cd s11_of(cd z, double z0 = 50) { return z / (z + 2 * z0); }

TEST(Transmission, TwoPortTouchstoneIsSeriesThrough) {
  const auto t = truth(21);
  std::string s = "! Agilent N5230A\n# Hz S RI R 50\n";
  for (std::size_t k = 0; k < t.f.size(); ++k) {
    const cd a = s11_of(t.z[k]), b = s21_of(t.z[k]);
    s += fmt("%.15g %.15g %.15g %.15g %.15g 0.5 0 %.15g %.15g\n", t.f[k], a.real(), a.imag(),
             b.real(), b.imag(), a.real(), a.imag());  // S11 S21 S12 S22
  }
  for (const char* name : {"x.s2p", "x.txt"}) {  // by the name, or by 9 values a line
    const auto c = read(s, name);
    EXPECT_EQ(c.format, ImpedanceFileFormat::Touchstone) << name;
    expect_curve(c, t, 1e-11, std::string("s2p series-through ") + name);
    EXPECT_TRUE(has_note(c, "device in series between the ports")) << name;
    EXPECT_NE(c.quantity.find("series-through"), std::string::npos);
  }
  // 2.0, 12_21 order, MA.
  std::string v2 =
      "[Version] 2.0\n# MHz S MA R 50\n[Number of Ports] 2\n[Two-Port Data Order] 12_21\n"
      "[Number of Frequencies] 21\n[Reference] 50 50\n[Network Data]\n";
  for (std::size_t k = 0; k < t.f.size(); ++k) {
    const cd a = s11_of(t.z[k]), b = s21_of(t.z[k]);
    v2 += fmt("%.15g %.15g %.15g 0.5 0\n  %.15g %.15g %.15g %.15g\n", t.f[k] / 1e6,
              std::abs(a), std::arg(a) * kDeg, std::abs(b), std::arg(b) * kDeg, std::abs(a),
              std::arg(a) * kDeg);  // S11 S12 S21 S22
  }
  v2 += "[End]\n";
  expect_curve(read(v2, "v2.s2p"), t, 1e-10, "s2p 2.0");
  // S21 at noise level: the device is on port 1, S11 a reflection.
  std::string one = "# Hz S RI R 50\n";
  for (std::size_t k = 0; k < t.f.size(); ++k) {
    const cd g = (t.z[k] - 50.0) / (t.z[k] + 50.0);
    one += fmt("%.15g %.15g %.15g 1e-5 2e-5 1e-5 2e-5 0.9 0.1\n", t.f[k], g.real(), g.imag());
  }
  const auto r = read(one, "port1.s2p");
  expect_curve(r, t, 1e-9, "s2p, S21 at noise level");
  EXPECT_TRUE(has_note(r, "S11 is read as a reflection"));
  // A two-port that is no series element (a filter: S11 + S21 far from 1): S11, said.
  std::string filt = "# Hz S RI R 50\n";
  for (std::size_t k = 0; k < t.f.size(); ++k) {
    const cd g = (t.z[k] - 50.0) / (t.z[k] + 50.0);
    filt += fmt("%.15g %.15g %.15g 0.5 0.5 0.5 0.5 0.1 0.1\n", t.f[k], g.real(), g.imag());
  }
  const auto fl = read(filt, "saw.s2p");
  expect_curve(fl, t, 1e-9, "s2p, not a series element");
  EXPECT_TRUE(has_note(fl, "not one element in series between the ports"));
  // A one-port S11 stays a reflection.
  std::string s1 = "# Hz S RI R 50\n";
  for (std::size_t k = 0; k < t.f.size(); ++k) {
    const cd g = (t.z[k] - 50.0) / (t.z[k] + 50.0);
    s1 += fmt("%.15g %.15g %.15g\n", t.f[k], g.real(), g.imag());
  }
  expect_curve(read(s1, "x.s1p"), t, 1e-9, "s1p reflection");
}

TEST(Transmission, S21ColumnsArePreferredToS11) {
  const auto t = truth(21);
  // A PNA CSV with S11 and S21 (dB, deg) and an equation trace: S21 read.
  std::string s = "Freq(Hz),Eq=(1-S11)/(1+S11)(DB),Eq=(1-S11)/(1+S11)(DEG),S11(DB),S11(DEG),"
                  "S21(DB),S21(DEG)\n";
  for (std::size_t k = 0; k < t.f.size(); ++k) {
    const cd a = s11_of(t.z[k]), b = s21_of(t.z[k]);
    s += fmt("%.15g,1,2,%.15g,%.15g,%.15g,%.15g\n", t.f[k], 20 * std::log10(std::abs(a)),
             std::arg(a) * kDeg, 20 * std::log10(std::abs(b)), std::arg(b) * kDeg);
  }
  const auto c = read(s, "pna.csv");
  expect_curve(c, t, 1e-10, "S21 columns");
  EXPECT_TRUE(has_note(c, "S21 is preferred to any S11 column"));
  EXPECT_TRUE(has_note(c, "an equation of other traces"));
  // S11 and S21 of a filter (S11 + S21 far from 1): S11, said.
  std::string f2 = "Freq(Hz),S11(DB),S11(DEG),S21(DB),S21(DEG)\n";
  for (std::size_t k = 0; k < t.f.size(); ++k) {
    const cd g = (t.z[k] - 50.0) / (t.z[k] + 50.0);
    f2 += fmt("%.15g,%.15g,%.15g,-3,170\n", t.f[k], 20 * std::log10(std::abs(g)),
              std::arg(g) * kDeg);
  }
  const auto fc = read(f2, "filter.csv");
  expect_curve(fc, t, 1e-9, "S11 of a filter");
  EXPECT_TRUE(has_note(fc, "not those of one element in series"));
  // vna/J in transmission mode: "Transmission Loss(dB)" and Phase; its Rs/Xs are not read.
  std::string v = "Frequency(Hz),Transmission Loss(dB),Phase(deg),Rs,SWR,Xs,|Z|,Theta\n";
  for (std::size_t k = 0; k < t.f.size(); ++k) {
    const cd b = s21_of(t.z[k]);
    v += fmt("%.15g,%.15g,%.15g,1,0.00,2,3,0.0\n", t.f[k], 20 * std::log10(std::abs(b)),
             std::arg(b) * kDeg);
  }
  const auto vj = read(v, "vnaj.csv");
  expect_curve(vj, t, 1e-10, "vna/J transmission");
  EXPECT_NE(vj.quantity.find("transmission S21"), std::string::npos);
}

// ------------------------------------------------------------------ --columns, headerless

TEST(Columns, NamedColumnsForAHeaderlessTable) {
  const auto t = truth(11);
  std::string s;
  for (std::size_t k = 0; k < t.f.size(); ++k) {
    const cd y = 1.0 / t.z[k];
    s += fmt("%.15g\t%.15g\t%.15g\t7\n", t.f[k] / 1e3, y.real() * 1e6, y.imag() * 1e6);
  }
  const auto c = read(s, "g.txt", "f[kHz],G[uS],B[uS],-");
  expect_curve(c, t, 1e-13, "--columns f[kHz],G[uS],B[uS],-");
  EXPECT_TRUE(has_note(c, "--columns f[kHz],G[uS],B[uS],-"));
  // Four columns without a header: refused, the message says how to name them.
  const std::string e = error_of(s, "lab/g.txt");
  EXPECT_EQ(e.rfind("lab/g.txt: line 1: no header, and 4 columns", 0), 0u) << e;
  EXPECT_NE(e.find("--columns f[Hz],R[ohm],X[ohm],-"), std::string::npos) << e;
  // Three columns without a header: f, R, X as always.
  std::string h;
  for (std::size_t k = 0; k < t.f.size(); ++k)
    h += fmt("%.15g,%.15g,%.15g\n", t.f[k], t.z[k].real(), t.z[k].imag());
  const auto r = read(h, "h.csv");
  expect_curve(r, t, 1e-13, "headerless f,R,X");
  EXPECT_TRUE(has_note(r, "no header: columns read as f_hz, re_ohm, im_ohm"));
  // |Z| alone by --columns: magnitude only; skip words.
  std::string m;
  for (std::size_t k = 0; k < t.f.size(); ++k) m += fmt("%.15g 1 %.15g\n", t.f[k], std::abs(t.z[k]));
  const auto mo = read(m, "m.txt", "f[Hz],skip,|Z|[ohm]");
  EXPECT_TRUE(mo.magnitude_only);
  EXPECT_NEAR(mo.z_ohm[3].real(), std::abs(t.z[3]), 1e-9 * std::abs(t.z[3]));
  // A leading '-' negates a column: a current's phase read as the impedance's.
  std::string ip;
  for (std::size_t k = 0; k < t.f.size(); ++k)
    ip += fmt("%.15g\t2.3\t%.15g\t%.15g\n", t.f[k], -std::arg(t.z[k]) * kDeg, std::abs(t.z[k]));
  const auto neg = read(ip, "i.txt", "f,skip,-theta(deg),|Z|");
  expect_curve(neg, t, 1e-13, "--columns with a negated phase");
  EXPECT_TRUE(has_note(neg, "negated as asked: [theta(deg)]"));
  // A header is skipped when columns are given.
  const auto hd = read("a,b,c\n" + h, "hd.csv", "f,R[ohm],X[ohm]");
  expect_curve(hd, t, 1e-13, "--columns over a header");
  // Bad specifications name the item.
  for (const auto& [spec, part] : std::vector<std::pair<std::string, std::string>>{
           {"f[Hz],Foo,B[S]", "'Foo' is not a column we know"},
           {"G[uS],B[uS]", "no frequency"},
           {"f[Hz],G[ohm],B[uS]", "'G[ohm]' is not a column we know"}}) {
    try {
      read(h, "h.csv", spec);
      ADD_FAILURE() << spec;
    } catch (const std::invalid_argument& ex) {
      EXPECT_NE(std::string(ex.what()).find(part), std::string::npos) << ex.what();
    }
  }
  // Too few or many fields for the names.
  EXPECT_NE(error_of(h, "h.csv", "f,R[ohm],X[ohm],D").find("3 columns, --columns names 4"),
            std::string::npos);
}

TEST(Columns, PaddedRowsAreSkippedNotRefused) {
  // A SARK-110 export written by a lab's control program: three sweeps side by
  // side, the shorter ones' columns empty below their end, and the file padded
  // with rows of separators only. Rows empty in the columns read are skipped
  // (said in a note); a row with some of them empty is still an error.
  const auto t = truth(11);
  std::string s = "freq_a,rs_a,xs_a,freq_b,rs_b,xs_b\n";
  for (std::size_t k = 0; k < t.f.size(); ++k)
    s += fmt("%.15g,%.15g,%.15g,%.15g,1,2\n", t.f[k], t.z[k].real(), t.z[k].imag(), t.f[k]);
  s += ",,,90e3,1,2\n,,,,,\n,,,,,\n";
  const auto c = read(s, "sark.csv", "f[Hz],R[ohm],X[ohm],-,-,-");
  expect_curve(c, t, 1e-13, "padded rows skipped");
  EXPECT_TRUE(has_note(c, "3 row(s) with empty fields in the columns read skipped"));
  const std::string e = error_of(s + "5e4,,,1,2,3\n", "sark.csv", "f[Hz],R[ohm],X[ohm],-,-,-");
  EXPECT_NE(e.find("is not a number"), std::string::npos) << e;
}

// ------------------------------------------------------------------ repeated frequencies, errors

TEST(Table, RepeatedFrequenciesAreAveraged) {
  // The MFIA export of a ZI blog: " Frequency  Resistance  Reactance", CR CR LF, a blank line,
  // the lowest frequency several times.
  std::string s = " Frequency      Resistance       Reactance\r\r\n\r\n";
  s += "   1.000000E-02    8.857049E+03    4.365435E+01\r\r\n";
  s += "   1.000000E-02    8.883777E+03   -1.657204E+00\r\r\n";
  s += "   2.000000E-02    8.862181E+03   -4.746084E+00\r\r\n";
  s += "   3.000000E-02    8.862000E+03   -5.000000E+00\r\r\n";
  const auto c = read(s, "mfia.csv");
  ASSERT_EQ(c.size(), 3u);
  EXPECT_NEAR(c.z_ohm[0].real(), (8.857049e3 + 8.883777e3) / 2, 1e-9);
  EXPECT_NEAR(c.z_ohm[0].imag(), (43.65435 - 1.657204) / 2, 1e-9);
  EXPECT_TRUE(has_note(c, "1 point(s) repeat the frequency"));
  // A file padded with rows of empty fields (SARK-110 via IMES): skipped, said.
  // Three sweeps side by side; the first is shorter.
  const auto p = read("freq__2019_,rs__2019_,xs__2019_,freq__b,rs__b,xs__b\n"
                      "4956111.0,7.09375,-921.5,1,2,3\n4956121.0,7.1,-921,2,2,3\n,,,3,2,3\n,,\n",
                      "sark.csv");
  ASSERT_EQ(p.size(), 2u);
  EXPECT_EQ(p.z_ohm[1], cd(7.1, -921));
  EXPECT_TRUE(has_note(p, "2 row(s) with empty fields in the columns read skipped"));
}

TEST(ImpedanceFiles, MessagesNameTheFileNotTheFunction) {
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"Foo,Bar,Baz\n1,2,3\n", "x.csv"},
      {"!Agilent Technologies,E4990A\nBEGIN CH1_DATA\nFrequency(Hz), Vac(V)-data\n1,2\nEND\n",
       "x.csv"},
      {"# Hz S RI R 50\n1 2 3 4\n", "x.s1p"},
      {"4294A REV1.11\n\"TRACE: A\"\n", "x.txt"},
      {"Frequency (Hz);Trace 1: Gain: Magnitude (dB)\n1;2\n", "x.csv"},
      {"\"No.\",\"FREQUENCY(Hz)\",\"G[S]\",\"OFF\"\r\n\"1\",\"1.0E+03\",\"1.0E-03\",\"\"\r\n",
       "x.csv"},
      {"frequency;Temperature\n1;2\n", "x.csv"},
  };
  for (const auto& [text, name] : bad) {
    const std::string e = error_of(text, name);
    EXPECT_EQ(e.rfind(name + ": ", 0), 0u) << e;
    EXPECT_EQ(e.find("read_"), std::string::npos) << e;
  }
  // "no impedance columns" says how to name them.
  EXPECT_NE(error_of("Freq,Temperature,Foo\n1,2,3\n").find("--columns"), std::string::npos);
  try {
    dsp::read_impedance_file("/nonexistent/z.csv");
    ADD_FAILURE();
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "/nonexistent/z.csv: cannot open the file");
  }
}

}  // namespace
