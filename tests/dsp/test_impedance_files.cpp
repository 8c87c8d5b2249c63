// dsp/impedance_files: every reader on texts written here from an analytic BVD
// impedance (so the truth is known), the three real HP 4294A files of EQCIRC3
// as they are, round trips through dsp/impedance_io's writers, and malformed
// inputs (named errors, never a crash).
//
// Tolerances follow from the printed precision: a value printed with p
// significant digits is within 0.5·10^(1−p) of itself, relatively. S11 → Z
// amplifies an error δS by |Z + z0|² / (2|Z| z0) (from Z = z0 (1+S)/(1−S)),
// up to ~1e3 on the BVD's anti-resonance (|Z| ≈ 1e5 Ω against 50 Ω).
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <cstdarg>
#include <cstdio>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "bvd_model.hpp"
#include "dsp/impedance_files/read_any.hpp"
#include "dsp/impedance_files/touchstone.hpp"
#include "dsp/impedance_io.hpp"
#include "dsp/uncertainty.hpp"

namespace {

using namespace piezo;
using dsp::ImpedanceFileFormat;
using cd = std::complex<double>;
constexpr double kDeg = 180.0 / std::numbers::pi;

std::string fmt(const char* f, ...) __attribute__((format(printf, 1, 2)));
std::string fmt(const char* f, ...) {
  char buf[512];
  va_list ap;
  va_start(ap, f);
  std::vsnprintf(buf, sizeof buf, f, ap);
  va_end(ap);
  return buf;
}

// One BVD mode, fr 50 kHz, fa 52 kHz, C0 2.5 nF, ζ 0.005: |Z| from ~25 Ω to ~1e5 Ω.
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
                            ImpedanceFileFormat hint = ImpedanceFileFormat::Auto) {
  std::istringstream in(text);
  return dsp::read_impedance_any(in, name, hint);
}

// |Z_read − Z| ≤ tol(Z)·|Z| at every point, frequencies to 1e-12.
template <class Tol>
void expect_curve(const dsp::ImportedImpedance& c, const Truth& t, Tol tol,
                  const std::string& what) {
  ASSERT_EQ(c.size(), t.f.size()) << what;
  for (std::size_t k = 0; k < t.f.size(); ++k) {
    EXPECT_NEAR(c.f_hz[k] / t.f[k], 1.0, 1e-12) << what << " point " << k;
    EXPECT_LE(std::abs(c.z_ohm[k] - t.z[k]), tol(t.z[k]) * std::abs(t.z[k]))
        << what << " point " << k << ": " << c.z_ohm[k] << " vs " << t.z[k];
  }
}
void expect_curve(const dsp::ImportedImpedance& c, const Truth& t, double rel,
                  const std::string& what) {
  expect_curve(
      c, t, [rel](cd) { return rel; }, what);
}

bool has_note(const dsp::ImportedImpedance& c, const std::string& part) {
  for (const auto& n : c.notes)
    if (n.find(part) != std::string::npos) return true;
  return false;
}

void expect_error(const std::string& text, const std::string& part,
                  const std::string& name = "x.csv",
                  ImpedanceFileFormat hint = ImpedanceFileFormat::Auto) {
  try {
    read(text, name, hint);
    ADD_FAILURE() << "no error for:\n" << text;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
  }
}

// ------------------------------------------------------------------ Touchstone

// Every parameter × format × version, frequency units in turn, references 50,
// 75 and 12.5 Ω; 12 significant digits.
TEST(Touchstone, EveryParameterFormatAndVersion) {
  const auto t = truth();
  const char* units[] = {"Hz", "kHz", "MHz", "GHz"};
  const double scale[] = {1, 1e3, 1e6, 1e9};
  int u = 0;
  for (int version : {1, 2})
    for (char param : {'S', 'Z', 'Y'})
      for (const char* form : {"RI", "MA", "DB"})
        for (double z0 : {50.0, 75.0, 12.5}) {
          u = (u + 1) % 4;
          std::string s = version == 2 ? "! v2\n[Version] 2.0\n" : "! v1\n";
          s += fmt("# %s %c %s R %g\n", units[u], param, form, z0);
          if (version == 2) {
            s += fmt("[Number of Ports] 1\n[Number of Frequencies] %zu\n", t.f.size());
            if (param == 'S') s += fmt("[Reference]\n%g\n", z0);
            s += "[Begin Information]\nanything\n[End Information]\n[Network Data]\n";
          }
          for (std::size_t k = 0; k < t.f.size(); ++k) {
            cd x = param == 'S'   ? (t.z[k] - z0) / (t.z[k] + z0)
                   : param == 'Z' ? t.z[k]
                                  : 1.0 / t.z[k];
            if (version == 1 && param == 'Z') x /= z0;  // 1.x normalizes Z and Y to R
            if (version == 1 && param == 'Y') x *= z0;
            const std::string f = fmt("%.12g", t.f[k] / scale[u]);
            const std::string a = std::string(form) == "RI" ? fmt("%.12g", x.real())
                                  : std::string(form) == "MA"
                                      ? fmt("%.12g", std::abs(x))
                                      : fmt("%.12g", 20 * std::log10(std::abs(x)));
            const std::string b =
                fmt("%.12g", std::string(form) == "RI" ? x.imag() : std::arg(x) * kDeg);
            // v2.0: a point may span lines.
            s += version == 2 && k % 7 == 3 ? f + " " + a + "\n  " + b + " ! split\n"
                                            : f + "\t" + a + "  " + b + "\n";
          }
          if (version == 2) s += "[End]\n! trailing comment\n";
          const auto c = read(s, "x.s1p");
          const std::string what = fmt("v%d %c %s z0 %g", version, param, form, z0);
          EXPECT_EQ(c.format, ImpedanceFileFormat::Touchstone) << what;
          EXPECT_EQ(c.format_name, version == 2 ? "Touchstone 2.0" : "Touchstone 1.x");
          expect_curve(
              c, t,
              [z0](cd z) { return 1e-11 * (2 + std::norm(std::abs(z) + z0) / (std::abs(z) * z0)); },
              what);
        }
}

TEST(Touchstone, DefaultsCaseAndOption) {
  // No option line: GHz, S, MA, R 50 (detected from the extension: numbers only).
  const auto c = read("1e-4 0 0\n2e-4 0.5 0\n3e-4 0.5 180\n", "x.s1p");
  ASSERT_EQ(c.size(), 3u);
  EXPECT_DOUBLE_EQ(c.f_hz[0], 1e5);
  EXPECT_NEAR(c.z_ohm[0].real(), 50, 1e-12);
  EXPECT_NEAR(c.z_ohm[1].real(), 150, 1e-9);
  EXPECT_NEAR(c.z_ohm[2].real(), 50.0 / 3, 1e-9);
  EXPECT_TRUE(has_note(c, "defaults"));
  const auto d = read("  # khz z ri r 2 ! lower case\n1 1 -1\n2 1 -2\n", "y.txt");
  EXPECT_EQ(d.format, ImpedanceFileFormat::Touchstone);
  EXPECT_EQ(d.z_ohm[1], cd(2, -4));  // 1.x: Z normalized to R = 2
  EXPECT_EQ(d.f_hz[1], 2000.0);
}

TEST(Touchstone, ErrorsAreNamed) {
  const auto ts = [](const std::string& s, const std::string& part) {
    expect_error(s, part, "x.s1p");
  };
  ts("# Hz S RI R 50\n1 0.1 0.2 0.3 0.4 0.5 0.6 0.7 0.8\n",
     "line 2: 9 values: a one-port line is 'f a b'");
  ts("# Hz H RI R 50\n1 0 0\n", "G and H parameters belong to two-port files");
  ts("[Version] 2.0\n# Hz S RI\n[Number of Ports] 3\n",
     "only one-port (.s1p) and two-port (.s2p) files are read");
  ts("[Version] 2.0\n# Hz S RI\n[Number of Ports] 1\n[Number of Frequencies] 3\n[Network Data]\n1 "
     "0 0\n2 0 0\n[End]\n",
     "[Number of Frequencies] is 3 but the file has 2 points");
  ts("# Hz S XX\n1 0 0\n", "unknown option 'XX'");
  ts("# Hz S RI R -5\n1 0 0\n", "R needs a positive reference resistance");
  ts("# Hz S RI R 50\n1 0 x\n", "line 2: 'x' is not a number");
  ts("[Version] 2.0\n# Hz S RI\n[Number of Ports] 1\n1 0 0\n", "data before [Network Data]");
  ts("[Version] 2.0\n# Hz S RI\n[Number of Ports] 1\n[Network Data]\n1 0 0\n2 0\n[End]\n",
     "value(s) left over");
  ts("[Version] 2.0\n# Hz S RI\n[Number of Ports] 1\n[Network Data]\n1 0 0\n[End]\n2 0 0\n",
     "content after [End]");
  ts("# Hz S RI R 50\n1 1 0\n", "impedance is not finite");  // S = 1: an open
  ts("# Hz S RI R 50\n2 0 0\n1 0 0\n3 0 0\n", "line 3: frequencies must be strictly ascending");
  ts("! only a comment\n# Hz S RI R 50\n", "no data rows");
  // The forced reader refuses what it cannot read even when it is a fine table.
  expect_error("f_hz,re_ohm,im_ohm\n1,2,3\n", "x.csv: line 1: 1 values", "x.csv",
               ImpedanceFileFormat::Touchstone);
}

// ------------------------------------------------------------------ HP 4294A

// The layout of the EQCIRC3 files, values printed as the analyzer does (%.6e).
std::string hp4294a(const std::string& parameter, const Truth& t, double (*a)(double, cd),
                    double (*b)(double, cd), bool memory = false) {
  std::string s =
      "4294A REV1.11\n\"DATE:     52 -100\"\n\n\n\"MEASURE PARAMETER: " + parameter + "\"\n";
  s += "\"ADAPTER: 7mm\"\n\"SWEEP TYPE: LOG FREQ\"\n" +
       fmt("\"NUMBER of POINTS: %zu\"\n", t.f.size());
  s += "\"POINT DELAY TIME:  0 Sec\"\n\"BW: 5\"\n\n\n";
  for (auto [name, v] : {std::pair{"A", a}, std::pair{"B", b}}) {
    s += fmt("\"TRACE: %s\"\n\"FORMAT: LOG\"\n\n", name);
    s += "\"Frequency\"\t\"Data Trace Real\"\t\"Data Trace Imag\"";
    s += memory ? "\t\"Memory Trace Real\"\t\"Memory Trace Imag\"\n" : "\n";
    for (std::size_t k = 0; k < t.f.size(); ++k) {
      s += fmt("%.11e\t%.6e\t%.6e", t.f[k], v(t.f[k], t.z[k]), 0.0);
      s += memory ? fmt("\t%.6e\t%.6e\n", 1.0, 0.0) : "\n";
    }
    s += "\n\n";
  }
  return s;
}

TEST(Hp4294a, ParametersOfBothTraces) {
  const auto t = truth();
  struct Case {
    const char* parameter;
    double (*a)(double, cd);
    double (*b)(double, cd);
    double tol;  // 7 digits of each trace
  };
  const Case cases[] = {
      {"IMPEDANCE MAG PHASE (DEG)", [](double, cd z) { return std::abs(z); },
       [](double, cd z) { return std::arg(z) * kDeg; }, 2e-6},
      {"ADMITTANCE MAG PHASE (DEG)", [](double, cd z) { return 1 / std::abs(z); },
       [](double, cd z) { return -std::arg(z) * kDeg; }, 2e-6},
      {"IMPEDANCE MAG PHASE (RAD)", [](double, cd z) { return std::abs(z); },
       [](double, cd z) { return std::arg(z); }, 2e-6},
      // The wording of these is our reading of the 4294A's parameter names (not seen in a real
      // file).
      {"R-X", [](double, cd z) { return z.real(); }, [](double, cd z) { return z.imag(); }, 2e-6},
      {"G-B", [](double, cd z) { return (1.0 / z).real(); },
       [](double, cd z) { return (1.0 / z).imag(); }, 2e-6},
      {"CP-D", [](double f, cd z) { return (1.0 / z).imag() / (2 * std::numbers::pi * f); },
       [](double, cd z) { return (1.0 / z).real() / std::abs((1.0 / z).imag()); }, 2e-6},
      {"LS-RS", [](double f, cd z) { return z.imag() / (2 * std::numbers::pi * f); },
       [](double, cd z) { return z.real(); }, 2e-6},
  };
  for (const auto& k : cases) {
    const auto c = read(hp4294a(k.parameter, t, k.a, k.b), "MD.txt");
    EXPECT_EQ(c.format, ImpedanceFileFormat::Hp4294a) << k.parameter;
    EXPECT_EQ(c.format_name, "HP 4294A text (4294A REV1.11)");
    expect_curve(c, t, k.tol, k.parameter);
  }
  const auto m = read(hp4294a(cases[0].parameter, t, cases[0].a, cases[0].b, true));
  expect_curve(m, t, 2e-6, "with memory columns");
  EXPECT_TRUE(has_note(m, "memory trace columns ignored"));
}

TEST(Hp4294a, ErrorsAreNamed) {
  const auto t = truth(6);
  const auto mag = [](double, cd z) { return std::abs(z); };
  const auto ph = [](double, cd z) { return std::arg(z) * kDeg; };
  const std::string good = hp4294a("IMPEDANCE MAG PHASE (DEG)", t, mag, ph);
  const auto cut = good.substr(0, good.find("\"TRACE: B\""));
  expect_error(cut,
               "no \"TRACE: B\" section: 'IMPEDANCE MAG PHASE (DEG)' needs trace A (magnitude) and "
               "trace B (phase)");
  std::string shifted = good;
  shifted.replace(shifted.rfind("4.4000000000"), 12, "4.4100000000");
  expect_error(shifted, "differs from trace A's");
  std::string fewer = good;
  fewer.replace(fewer.find("POINTS: 6"), 9, "POINTS: 7");
  expect_error(fewer, "NUMBER of POINTS is 7 but the traces have 6 rows");
  std::string complex = good;
  complex.replace(complex.find("0.000000e+00"), 12, "1.000000e+00");
  expect_error(complex, "the imaginary column is not zero");
  std::string odd = good;
  odd.replace(odd.find("IMPEDANCE MAG PHASE (DEG)"), 25, "|Z|-LS");
  expect_error(odd, "MEASURE PARAMETER '|Z|-LS' is not read");
  std::string none = good;
  none.replace(none.find("MEASURE PARAMETER"), 17, "MEASURE THING");
  expect_error(none, "no \"MEASURE PARAMETER: ...\" line");
}

// The three real files of EQCIRC3 (fixtures/eqcirc3), read as they are.
TEST(Hp4294a, Eqcirc3FilesReadAsTheyAre) {
  const std::string dir = PIEZO_SOURCE_DIR "/fixtures/eqcirc3/";
  const auto argmin = [](const dsp::ImportedImpedance& c) {
    std::size_t k = 0;
    for (std::size_t i = 1; i < c.size(); ++i)
      if (std::abs(c.z_ohm[i]) < std::abs(c.z_ohm[k])) k = i;
    return k;
  };
  const auto md1 = dsp::read_impedance_file(dir + "MD1.txt");
  EXPECT_EQ(md1.format, ImpedanceFileFormat::Hp4294a);
  ASSERT_EQ(md1.size(), 801u);
  EXPECT_DOUBLE_EQ(md1.f_hz.front(), 25500.0);
  EXPECT_DOUBLE_EQ(md1.f_hz.back(), 32500.0);
  const auto m = argmin(md1);
  std::printf("[eqcirc3] MD1: %zu points, %.1f-%.1f Hz, |Z| min %.4g ohm at %.1f Hz; %s\n",
              md1.size(), md1.f_hz.front(), md1.f_hz.back(), std::abs(md1.z_ohm[m]), md1.f_hz[m],
              md1.quantity.c_str());
  // The grid minimum of |Z|, not a fit: EQCIRC3's fr (28 166.7 Hz) comes from its
  // L1 C1; the minimum sits 0.25 % below it on this file.
  EXPECT_NEAR(md1.f_hz[m] / 28166.7, 1.0, 5e-3);
  EXPECT_NEAR(std::abs(md1.z_ohm[m]), 175.9406, 1e-4);
  // MD1's phase runs from +94° to +252°: as written it is not passive (noted, kept).
  EXPECT_NEAR(std::arg(md1.z_ohm[0]) * kDeg, 94.18821, 1e-5);
  EXPECT_TRUE(has_note(md1, "not a passive impedance"));

  const auto rb = dsp::read_impedance_file(dir + "RB5100.txt");
  ASSERT_EQ(rb.size(), 601u);
  EXPECT_DOUBLE_EQ(rb.f_hz.front(), 74000.0);
  EXPECT_DOUBLE_EQ(rb.f_hz.back(), 316400.0);
  const auto r = argmin(rb);
  std::printf("[eqcirc3] RB5100: %zu points, %.1f-%.1f Hz, |Z| min %.4g ohm at %.1f Hz\n",
              rb.size(), rb.f_hz.front(), rb.f_hz.back(), std::abs(rb.z_ohm[r]), rb.f_hz[r]);
  EXPECT_NEAR(rb.f_hz[r] / 154.4e3, 1.0, 5e-3);
  EXPECT_NEAR(std::arg(rb.z_ohm[0]) * kDeg, -88.83969, 1e-5);  // capacitive below resonance
  EXPECT_TRUE(has_note(rb, "memory trace columns ignored"));
  EXPECT_FALSE(has_note(rb, "not a passive impedance"));

  const auto ya = dsp::read_impedance_file(dir + "sampleadmittance.txt");
  ASSERT_EQ(ya.size(), 801u);
  EXPECT_DOUBLE_EQ(ya.f_hz.front(), 100000.0);
  EXPECT_DOUBLE_EQ(ya.f_hz.back(), 130000.0);
  EXPECT_NE(ya.quantity.find("admittance |Y| and phase"), std::string::npos) << ya.quantity;
  EXPECT_NEAR(std::abs(ya.z_ohm[0]), 1 / 1.103217e-3, 1e-9);
  EXPECT_NEAR(std::arg(ya.z_ohm[0]) * kDeg, 90.68633, 1e-5);  // Z's phase is −Y's
  const auto y = argmin(ya);
  std::printf("[eqcirc3] sampleadmittance: %zu points, %.1f-%.1f Hz, |Z| min %.4g ohm at %.1f Hz\n",
              ya.size(), ya.f_hz.front(), ya.f_hz.back(), std::abs(ya.z_ohm[y]), ya.f_hz[y]);
  EXPECT_NEAR(std::abs(ya.z_ohm[y]), 1 / 0.00961523, 1e-6);
}

// ------------------------------------------------------------------ tables

TEST(Table, RoundTripWithImpedanceIo) {
  const auto t = truth();
  dsp::ImpedanceResult r;
  r.method = "prony";
  r.f_hz = Eigen::Map<const Eigen::VectorXd>(t.f.data(), static_cast<Eigen::Index>(t.f.size()));
  r.z_ohm = Eigen::Map<const Eigen::VectorXcd>(t.z.data(), static_cast<Eigen::Index>(t.z.size()));
  std::ostringstream csv;
  dsp::write_impedance_csv(csv, r);
  const auto c = read(csv.str(), "z.csv");
  EXPECT_EQ(c.format, ImpedanceFileFormat::Table);
  EXPECT_TRUE(c.abs_sigma_ohm.empty());
  expect_curve(c, t, 1e-9, "write_impedance_csv");  // %.10g per component

  Eigen::VectorXd sigma(r.f_hz.size());
  for (Eigen::Index k = 0; k < sigma.size(); ++k)
    sigma[k] = 1e-3 * std::abs(r.z_ohm[k]) * (1 + k % 3);
  const auto band = dsp::band_from_sigma(r.f_hz, r.z_ohm, sigma, 1.96);
  std::ostringstream wide;
  dsp::write_impedance_csv(wide, r, band);
  const auto w = read(wide.str(), "band.csv");
  expect_curve(w, t, 1e-9, "write_impedance_csv with band");
  ASSERT_EQ(w.abs_sigma_ohm.size(), t.f.size());
  for (std::size_t k = 0; k < t.f.size(); ++k) {  // σ printed with %.6g: 5e-6
    EXPECT_NEAR(w.abs_sigma_ohm[k] / band.abs_sigma_ohm[static_cast<Eigen::Index>(k)], 1, 5e-6);
    EXPECT_NEAR(w.phase_sigma_rad[k] / band.phase_sigma_rad[static_cast<Eigen::Index>(k)], 1, 5e-6);
  }
  EXPECT_EQ(w.coverage_factor, 1.96);

  for (double ref : {50.0, 75.0}) {
    std::ostringstream ts;
    dsp::write_touchstone_s1p(ts, r, ref);
    const auto s = read(ts.str(), "z.s1p");
    EXPECT_EQ(s.format, ImpedanceFileFormat::Touchstone);
    expect_curve(s, t, 1e-9, "write_touchstone_s1p");  // %.10g of Z/R, R exact
  }
}

// Usual column names, units and separators; values printed with 9 digits
// (5e-9 each; a magnitude, a phase of up to 180° and a frequency add up to
// ~2e-8; in dB, 5e-9 of ~100 dB is 6e-8 of |Z|).
TEST(Table, ColumnNamesUnitsAndSeparators) {
  const auto t = truth();
  struct Case {
    const char* header;
    char sep;
    bool decimal_comma;
    std::vector<double> (*row)(double f, cd z);
    double tol;
  };
  using V = std::vector<double>;
  const Case cases[] = {
      {"Frequency (kHz),|Z| (kOhm),Phase (deg)", ',', false,
       [](double f, cd z) {
         return V{f / 1e3, std::abs(z) / 1e3, std::arg(z) * kDeg};
       },
       3e-8},
      {"freq;R (Ohm);X (Ohm)", ';', true,
       [](double f, cd z) {
         return V{f, z.real(), z.imag()};
       },
       3e-8},
      {"f [MHz]\tG [mS]\tB [mS]", '\t', false,
       [](double f, cd z) {
         return V{f / 1e6, (1.0 / z).real() * 1e3, (1.0 / z).imag() * 1e3};
       },
       3e-8},
      {"Frequency (Hz)   |Y| (uS)   Phase (rad)", ' ', false,
       [](double f, cd z) {
         return V{f, 1e6 / std::abs(z), -std::arg(z)};
       },
       3e-8},
      {"f_hz,Z_dB,phase_deg", ',', false,
       [](double f, cd z) {
         return V{f, 20 * std::log10(std::abs(z)), std::arg(z) * kDeg};
       },
       1e-7},
      {"Frequency(Hz), Cp(F)-data, D()-data, Cp(F)-mem", ',', false,
       [](double f, cd z) {
         const cd y = 1.0 / z;
         return V{f, y.imag() / (2 * std::numbers::pi * f), y.real() / std::abs(y.imag()), 0.0};
       },
       3e-8},
  };
  for (const auto& k : cases) {
    std::string s = std::string(k.header) + "\n";
    for (std::size_t i = 0; i < t.f.size(); ++i) {
      const auto v = k.row(t.f[i], t.z[i]);
      for (std::size_t j = 0; j < v.size(); ++j) {
        std::string x = fmt("%.9g", v[j]);
        if (k.decimal_comma)
          for (auto& ch : x) ch = ch == '.' ? ',' : ch;
        s += (j ? std::string(1, k.sep == ' ' ? ' ' : k.sep) : "") + x;
      }
      s += "\n";
    }
    const auto c = read(s);
    expect_curve(c, t, k.tol, k.header);
  }
  // Plain "f,re,im": no unit, no quantity: impedance and Hz assumed, said so.
  const auto p = read("f,re,im\n1,2,3\n2,4,5\n");
  EXPECT_EQ(p.z_ohm[1], cd(4, 5));
  EXPECT_TRUE(has_note(p, "read as impedance"));
  EXPECT_TRUE(has_note(p, "Hz assumed"));
  // A header in the comment above the data (Copper Mountain VNAs): S11, z0 = 50 Ω assumed.
  const auto s11 = read("! CMT, S2VNA\n! Stimulus(Hz), Re(S11), Im(S11)\n1e6, 0.2, 0\n2e6, 0, 0\n");
  EXPECT_NEAR(s11.z_ohm[0].real(), 75.0, 1e-12);
  EXPECT_TRUE(has_note(s11, "z0 = 50 ohm assumed"));
  // Descending sweeps are reversed.
  const auto d = read("f_hz,re_ohm,im_ohm\n3,1,0\n2,2,0\n1,3,0\n");
  EXPECT_EQ(d.f_hz, (std::vector<double>{1, 2, 3}));
  EXPECT_EQ(d.z_ohm[0], cd(3, 0));
  EXPECT_TRUE(has_note(d, "reversed"));
  // Headerless, as update/'s CSV always allowed.
  const auto h = read("1,1,-1\n2,1,-0.5\n");
  EXPECT_EQ(h.z_ohm[1], cd(1, -0.5));
}

TEST(Table, ErrorsAreNamed) {
  expect_error("Foo,Bar,Baz\n1,2,3\n", "x.csv: line 1: no frequency column among [Foo, Bar, Baz]");
  expect_error("f_hz,re_ohm,im_ohm\n1,2,3\n2,3\n", "x.csv: line 3: 2 columns, the header has 3");
  expect_error("Freq,Temperature,Foo\n1,2,3\n",
               "no impedance columns among [Freq, Temperature, Foo]");
  expect_error("f_hz,re_ohm,im_ohm\n1,2,3\n2,2,x\n",
               "line 3: 'x' is not a number (column 'im_ohm')");
  expect_error("f_hz,re_ohm,im_ohm\n1,2,3\n3,2,3\n2,2,3\n",
               "line 4: frequencies must be strictly ascending");
  expect_error("", "no data rows");
  expect_error("f_hz,re_ohm,im_ohm\n", "no data rows under the header 'f_hz,re_ohm,im_ohm'");
  expect_error("f_hz,re_ohm,im_ohm\n1,inf,0\n", "impedance is not finite");
  expect_error("f_hz,|Z|,phase\n1,-2,0\n", "impedance is not finite");  // negative magnitude
  expect_error("1,2\n2,3\n",
               "a table without a header is read only as the three columns f_hz, re_ohm, im_ohm");
  expect_error(
      "Frequency (Hz);Trace 1: Gain: Magnitude (dB);Trace 1: Gain: Phase (\xC2\xB0)\n1;2;3\n",
      "no impedance columns among");
}

// ------------------------------------------------------------------ instruments

// The Bode Analyzer Suite's export: BOM, CR LF, ';', Ω as U+2126, a repeated column.
TEST(Bode100, ExportAndVariants) {
  const auto t = truth(12);
  std::string s =
      "\xEF\xBB\xBF"
      "Frequency (Hz);Trace 1: Impedance: Real (\xE2\x84\xA6);Trace 1: Impedance: "
      "Imaginary (\xE2\x84\xA6);Trace 1: Impedance: Real (\xE2\x84\xA6)\r\n";
  for (std::size_t k = 0; k < t.f.size(); ++k)
    s += fmt("%.15g;%.15g;%.15g;%.15g\r\n", t.f[k], t.z[k].real(), t.z[k].imag(), t.z[k].real());
  s += "\r\n";
  EXPECT_EQ(dsp::detect_impedance_format(s, "bode.csv"), ImpedanceFileFormat::Bode100);
  const auto c = read(s, "bode.csv");
  EXPECT_EQ(c.format, ImpedanceFileFormat::Bode100);
  expect_curve(c, t, 2e-14, "Bode 100 real/imaginary");  // %.15g

  // Magnitude/phase with decimal commas and a Latin-1 degree sign (not seen in a real file).
  std::string m =
      "Frequency (Hz);Trace 1: Impedance: Magnitude (\xCE\xA9);Trace 2: Impedance: Phase (\xB0)\n";
  for (std::size_t k = 0; k < t.f.size(); ++k) {
    std::string row = fmt("%.12g;%.12g;%.12g\n", t.f[k], std::abs(t.z[k]), std::arg(t.z[k]) * kDeg);
    for (auto& ch : row) ch = ch == '.' ? ',' : ch;
    m += row;
  }
  const auto d = read(m, "bode.csv");
  EXPECT_EQ(d.format, ImpedanceFileFormat::Bode100);
  expect_curve(d, t, 3e-11, "Bode 100 magnitude/phase");  // %.12g
  EXPECT_TRUE(has_note(d, "decimal commas"));
}

// The E4990A help's example layout: two channels, title and DC monitor lines.
TEST(E4990a, ExportBlocksAndVariants) {
  const auto t = truth(11);  // a 2 kHz step: frequencies exact in 12 digits
  std::string s =
      "!Agilent Technologies,E4990A,MY521012345,A.02.10\n!Date: Fri Apr 03 13:41:16 2015\n";
  s += "BEGIN CH1_DATA\nTitle label, TEST DATA\nDCV(V), +5.230e-005, DCI(A), +2.335e-005\n";
  s += "Frequency(Hz), |Z|(Ohm)-data, theta-z(deg)-data, theta-z(deg)-mem\n";
  for (std::size_t k = 0; k < t.f.size(); ++k)
    s += fmt("%+.11e, %+.11e, %+.11e, %+.11e\n", t.f[k], std::abs(t.z[k]), std::arg(t.z[k]) * kDeg,
             1.0);
  s += "END\nBEGIN CH2_DATA\nFrequency(Hz), Z-Real(Ohm)-data, Z-Imag(Ohm)-data, Y-Real(S)-mem, "
       "Y-Imag(S)-mem\n";
  for (std::size_t k = 0; k < t.f.size(); ++k)
    s += fmt("%+.11e, %+.11e, %+.11e, +1e-3, +1e-3\n", t.f[k], t.z[k].real(), t.z[k].imag());
  s += "END\n";
  EXPECT_EQ(dsp::detect_impedance_format(s, "e.csv"), ImpedanceFileFormat::E4990a);
  const auto c = read(s, "e.csv");
  EXPECT_EQ(c.format, ImpedanceFileFormat::E4990a);
  EXPECT_NE(c.format_name.find("E4990A"), std::string::npos);
  expect_curve(c, t, 3e-11, "E4990A |Z| theta");  // %+.11e: 12 digits
  EXPECT_TRUE(has_note(c, "block CH2_DATA (line"));
  EXPECT_TRUE(has_note(c, "theta-z(deg)-mem (memory trace)"));

  // R-X with decimal commas under comma separators: every value split in two.
  std::string dc =
      "!Keysight Technologies,E4990A,MY1,A.03\nBEGIN CH1_DATA\nFrequency(Hz), R(Ohm)-data, "
      "X(Ohm)-data\n";
  for (std::size_t k = 0; k < t.f.size(); ++k) {
    std::string row = fmt("%+.11e,%+.11e,%+.11e\n", t.f[k], t.z[k].real(), t.z[k].imag());
    std::string out;
    for (char ch : row) out += ch == '.' ? ',' : ch;
    dc += out;
  }
  dc += "END\n";
  const auto d = read(dc, "e.csv");
  expect_curve(d, t, 3e-11, "E4990A decimal commas");
  EXPECT_TRUE(has_note(d, "split in two"));

  expect_error(
      "!Agilent Technologies,E4990A\nBEGIN CH1_DATA\nFrequency(Hz), |Z|(Ohm)-data, "
      "theta-z(deg)-data\n1,2,3\n",
      "BEGIN CH1_DATA has no END (file cut short?)");
  expect_error(
      "!Agilent Technologies,E4990A\nBEGIN CH1_DATA\nFrequency(Hz), Vac(V)-data\n1,2\nEND\n",
      "x.csv: line 3: no impedance columns among [Frequency(Hz), Vac(V)-data]");
}

// Malformed files: every reader, seeded byte edits of valid texts; each read
// either succeeds with a valid curve or throws std::invalid_argument.
TEST(ImpedanceFiles, MutatedInputsNeverCrash) {
  const auto t = truth(8);
  const auto mag = [](double, cd z) { return std::abs(z); };
  const auto ph = [](double, cd z) { return std::arg(z) * kDeg; };
  const std::vector<std::string> seeds = {
      hp4294a("IMPEDANCE MAG PHASE (DEG)", t, mag, ph),
      "[Version] 2.0\n# MHz Y MA R 50\n[Number of Ports] 1\n[Number of Frequencies] 2\n[Reference] "
      "75\n"
      "[Network Data]\n1 0.5 10\n2 0.4 20\n[End]\n",
      "!Agilent Technologies,E4990A\nBEGIN CH1_DATA\nFrequency(Hz), |Z|(Ohm)-data, "
      "theta-z(deg)-data\n1,2,3\n2,3,4\nEND\n",
      "Frequency (Hz);Trace 1: Impedance: Magnitude (\xCE\xA9);Trace 2: Impedance: Phase "
      "(\xC2\xB0)\n1;2;3\n2;3,5;4\n",
      "f_hz,re_ohm,im_ohm,abs_ohm,abs_sigma_ohm,phase_deg,phase_sigma_deg,coverage_factor\n1,2,3,4,"
      "5,6,7,8\n",
  };
  std::mt19937_64 rng(34);
  const std::string alphabet =
      "0123456789.,;\t \n\r-+eE#![]\"|()abcdefghijklmnopqrstuvwxyzRIMADBSZY:";
  int ok = 0, refused = 0;
  for (const auto& seed : seeds) {
    for (int trial = 0; trial < 300; ++trial) {
      std::string s = seed;
      const int edits = 1 + static_cast<int>(rng() % 4);
      for (int e = 0; e < edits && !s.empty(); ++e) {
        const std::size_t at = rng() % s.size();
        switch (rng() % 3) {
          case 0:
            s[at] = alphabet[rng() % alphabet.size()];
            break;
          case 1:
            s.erase(at, 1 + rng() % 8);
            break;
          default:
            s.insert(at, 1, alphabet[rng() % alphabet.size()]);
        }
      }
      for (auto hint : {ImpedanceFileFormat::Auto, ImpedanceFileFormat::Table,
                        ImpedanceFileFormat::Touchstone, ImpedanceFileFormat::Hp4294a,
                        ImpedanceFileFormat::E4990a, ImpedanceFileFormat::Bode100}) {
        try {
          const auto c = read(s, "m.txt", hint);
          ++ok;
          ASSERT_GE(c.size(), 1u);
          for (std::size_t k = 0; k < c.size(); ++k) {
            ASSERT_TRUE(std::isfinite(c.f_hz[k]) && c.f_hz[k] >= 0);
            ASSERT_TRUE(k == 0 || c.f_hz[k] > c.f_hz[k - 1]);
            ASSERT_TRUE(std::isfinite(std::abs(c.z_ohm[k])));
          }
        } catch (const std::invalid_argument&) {
          ++refused;
        }
      }
    }
  }
  std::printf("[mutations] %d read, %d refused\n", ok, refused);
  EXPECT_GT(ok, 0);
  EXPECT_GT(refused, 0);
}

}  // namespace
