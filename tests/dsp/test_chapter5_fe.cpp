// Seed chapter 5.1.2 on OUR FE model (fe_chapter5.hpp: the published APC850
// tube's modal port model, β = 1e-7, 500 V·e^{−0.001 t} from t = 0 through
// R1 = 3140 Ω, 10 MS/s, 5 ms records, noise per channel = level·std(clean
// channel over the record)). CI part: one noise seed per level; the statistics
// over seeds are in test_chapter5_fe_study.cpp (label validate).
//
// Targets (acceptance): features within 0.2 %, |Z| within 1 dB over 1–120 kHz
// away from the peaks (±1.5 % around each true feature). Asserted where the
// information in the data allows them. Where it does not, the Cramér–Rao bound
// (crb.hpp, delta method on the |Z| extrema) is asserted as the reason, and the
// achieved error is asserted against a tolerance derived from that bound:
//   * 10 % noise: the reduced-model CRB of five of the six features is above
//     0.2 % (1σ) with 1000 and with 3000 samples — on the FE tube the divider's
//     v2 carries far less ring-down than on the BVD stand-in (10.3 nF instead of
//     3.8 nF: |Z| three times lower at the modes, noise set by the charging
//     step), and the |Z| minima are zeros of V2, where v2 has least signal.
//   * 1 % noise: the CRB of the close pair's features is 0.12–0.20 % (1σ) at
//     3000 samples, so no estimator meets 0.2 % there on every record.
//   * 0.1 % noise: every target is met with 3000 samples.
// The test regenerates build/chapter5-comparison.svg (docs/ holds a copy).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "fe_chapter5.hpp"
#include "impedance_study.hpp"
#include "study_plot.hpp"

namespace {
using namespace piezo;
using cd = std::complex<double>;

const fe5::FeChapter5& fe() { return fe5::chapter5(); }

void print_bounds(const char* what, const fe5::FeatureBounds& b) {
  std::printf("%s CRB (1σ) %%: resonances", what);
  for (double x : b.res_rel) std::printf(" %.3f", 100 * x);
  std::printf("; anti-resonances");
  for (double x : b.anti_rel) std::printf(" %.3f", 100 * x);
  std::printf("\n");
}

// Frequencies of the |Z| score (1–120 kHz away from the peaks) on a 200 Hz grid.
std::vector<double> scored_grid(const study::StudyInput& in) {
  std::vector<double> f;
  for (double x = in.f_lo_hz; x <= in.f_hi_hz; x += 200.0)
    if (!study::near_feature(in, x)) f.push_back(x);
  return f;
}

// The FE transient (model/transient.hpp) and the pole–residue form the CRBs
// use are the same response, and its Z is the port model's Z: the bounds are
// computed on the study's data.
TEST(Chapter5Fe, TransientAndPoleResidueFormAreTheSameResponse) {
  const auto& d = fe();
  ASSERT_EQ(d.v2.size(), d.record);
  double worst = 0;
  for (std::size_t k = 0; k < d.record; ++k)
    worst = std::max(worst, std::abs(d.exact.v2.at(double(k) / d.sample_rate_hz) - d.v2[k]));
  EXPECT_LT(worst, 1e-9 * d.amplitude_v) << "max |v2 transient − v2 pole–residue| (V)";
  for (double f : {1e3, 50e3, 79e3, 95e3, 120e3}) {
    const cd s(0, 2 * M_PI * f);
    const cd z = d.r1_ohm * d.exact.v2.laplace(s) / (d.exact.v1.laplace(s) - d.exact.v2.laplace(s));
    EXPECT_LT(std::abs(z / d.z(f) - 1.0), 1e-9) << f << " Hz";
  }
  // The truth: three resonance / anti-resonance pairs in 1–120 kHz (the weakly
  // coupled symmetric mode at 83.9 kHz makes no extremum above 0.3 dB).
  const auto in = fe5::study_input(d, 0.01, 1, 1);
  ASSERT_EQ(in.true_resonances_hz.size(), 3u);
  ASSERT_EQ(in.true_antiresonances_hz.size(), 3u);
  std::printf("true |Z| extrema (Hz): resonances %.1f %.1f %.1f, anti-resonances %.1f %.1f %.1f\n",
              in.true_resonances_hz[0], in.true_resonances_hz[1], in.true_resonances_hz[2],
              in.true_antiresonances_hz[0], in.true_antiresonances_hz[1],
              in.true_antiresonances_hz[2]);
  std::printf("noise std at 10 %%: v1 %.3g V, v2 %.3g V\n", fe5::noise_std(d, 0.1).first,
              fe5::noise_std(d, 0.1).second);
}

// 0.1 % noise (S/N 60 dB): every target met with 3000 samples.
TEST(Chapter5Fe, PerMilleNoiseMeetsTargetsWith3000Samples) {
  const auto in = fe5::study_input(fe(), 0.001, 1, 1);
  const auto r = study::study_prony(in, 3000);
  std::printf("FE, 0.1 %% noise, seed 1\n%s", study::format_table({r}).c_str());
  for (std::size_t m = 0; m < 3; ++m) {
    EXPECT_LT(std::abs(r.res_err_rel.at(m)), 2e-3) << "resonance " << m;
    EXPECT_LT(std::abs(r.anti_err_rel.at(m)), 2e-3) << "anti-resonance " << m;
  }
  EXPECT_LT(r.max_db_err, 1.0);
}

// 1 % noise (S/N 40 dB): Prony-SS with 3000 samples beside the direct FFT (one
// record of 5e4) and the cross spectra (20 records of 5e4).
TEST(Chapter5Fe, OnePercentNoiseComparison) {
  const auto in = fe5::study_input(fe(), 0.01, 1, 20);
  const auto p1000 = study::study_prony(in, 1000), p3000 = study::study_prony(in, 3000);
  const auto fft = study::study_fft(in, true), xs = study::study_xspec(in, 50000, true);
  std::printf("FE, 1 %% noise, seed 1\n%s", study::format_table({p1000, p3000, fft, xs}).c_str());
  const auto crb = fe5::feature_crb(fe(), in, 0.01, 3000, fe5::CrbClass::Reduced);
  print_bounds("3000 samples, reduced model,", crb);

  // |Z| away from the peaks: within 1 dB with 3000 samples; the FFT-based
  // methods are worse there (their worst bins sit next to the deep minima).
  EXPECT_LT(p3000.max_db_err, 1.0);
  EXPECT_LT(p3000.max_db_err, fft.max_db_err);
  EXPECT_LT(p3000.max_db_err, xs.max_db_err);
  // Mode 3's anti-resonance (CRB 0.014 %): within the target.
  EXPECT_LT(std::abs(p3000.anti_err_rel.at(2)), 2e-3);
  // The close pair (modes 1-2): the bound itself is 0.12–0.20 % (1σ), so 0.2 %
  // cannot be required of one record; all four features are resolved and lie
  // within 2.5 × the largest of those bounds.
  double largest = 0;
  for (std::size_t m = 0; m < 2; ++m) {
    EXPECT_GT(crb.res_rel[m], 1e-3);
    EXPECT_GT(crb.anti_rel[m], 1e-3);
    largest = std::max({largest, crb.res_rel[m], crb.anti_rel[m]});
  }
  for (std::size_t m = 0; m < 2; ++m) {
    EXPECT_LT(std::abs(p3000.res_err_rel.at(m)), 2.5 * largest) << "resonance " << m;
    EXPECT_LT(std::abs(p3000.anti_err_rel.at(m)), 2.5 * largest) << "anti-resonance " << m;
  }
  // Mode 3's resonance: the order-8 fit leaves out the FE tube's modes above the
  // band (231 kHz and up), whose tails enter V2 next to its zero at 79.1 kHz:
  // a bias of +0.16 % at this noise (validate study: +0.165 ± 0.053 % over 100
  // seeds; +0.05 % where the order reaches 10 at 0.1 % noise). Within 0.2 %
  // here, asserted as achieved, with 0.3 % = bias + 2σ as the tolerance.
  EXPECT_LT(std::abs(p3000.res_err_rel.at(2)), 3e-3);
  // 1000 samples do not resolve the pair at 1 % (CRB several %): documented in
  // the table, not asserted.
}

// The seed's case, 10 % noise (S/N 20 dB), seed 1: the comparison table and the
// figure. What the data allow is asserted through the bounds.
TEST(Chapter5Fe, TenPercentNoiseTableBoundsAndPlot) {
  const auto in = fe5::study_input(fe(), 0.10, 1, 20);
  const std::vector<study::StudyRow> rows{
      study::study_prony(in, 1000),         study::study_prony(in, 3000),
      study::study_fft(in, false),          study::study_fft(in, true),
      study::study_xspec(in, 50000, false), study::study_xspec(in, 50000, true)};
  std::printf("FE, 10 %% noise, seed 1\n%s", study::format_table(rows).c_str());

  const auto r1000 = fe5::feature_crb(fe(), in, 0.10, 1000, fe5::CrbClass::Reduced);
  const auto r3000 = fe5::feature_crb(fe(), in, 0.10, 3000, fe5::CrbClass::Reduced);
  const auto f3000 = fe5::feature_crb(fe(), in, 0.10, 3000, fe5::CrbClass::Full);
  const auto r50k = fe5::feature_crb(fe(), in, 0.10, 50000, fe5::CrbClass::Reduced);
  print_bounds("1000 samples, reduced model,", r1000);
  print_bounds("3000 samples, reduced model,", r3000);
  print_bounds("3000 samples, full model,   ", f3000);
  print_bounds("50000 samples, reduced model,", r50k);
  // Beyond the information in one record, for any unbiased estimator: all three
  // resonances and the anti-resonances of modes 1-2, with 1000, 3000 and even
  // all 50000 samples. Mode 3's anti-resonance is within reach with 3000.
  for (const auto* b : {&r1000, &r3000, &r50k}) {
    for (std::size_t m = 0; m < 3; ++m) EXPECT_GT(b->res_rel[m], 2e-3) << "resonance " << m;
    for (std::size_t m = 0; m < 2; ++m) EXPECT_GT(b->anti_rel[m], 2e-3) << "anti-resonance " << m;
  }
  EXPECT_LT(r3000.anti_rel[2], 2e-3);
  // Prony with 3000 samples there: within 3σ of that bound.
  EXPECT_LT(std::abs(rows[1].anti_err_rel.at(2)), 3 * r3000.anti_rel[2]);
  // |Z| away from the peaks: Prony's median error is the lowest; the raw FFT of
  // a step held to the record's end is meaningless (V1(f_k) ≈ 0 off DC).
  EXPECT_LT(rows[1].median_db_err, rows[3].median_db_err);
  EXPECT_LT(rows[1].median_db_err, rows[5].median_db_err);
  EXPECT_GT(rows[2].median_db_err, 3.0);
  // The 1 dB max target: the bound of 20·log10|Z| itself exceeds 1 dB inside the
  // pair (between 50.8 and 51 kHz) with 3000 samples.
  const auto grid = scored_grid(in);
  const auto db3000 = fe5::db_crb(fe(), 0.10, 3000, grid, fe5::CrbClass::Reduced);
  const auto worst = std::max_element(db3000.begin(), db3000.end());
  std::printf("CRB of 20 log10|Z| away from the peaks, 3000 samples: max %.2f dB at %.1f kHz\n",
              *worst, grid[std::size_t(worst - db3000.begin())] / 1e3);
  EXPECT_GT(*worst, 1.0);

  // The figure: Prony 1000 / 3000, FFT and cross spectra (differenced), with the
  // CRB band of 3000 samples in the error panel.
  const std::vector<study::StudyRow> shown{rows[3], rows[5], rows[0], rows[1]};
  std::vector<double> fb;
  for (double f = in.f_lo_hz; f <= in.f_hi_hz; f *= 1.004) fb.push_back(f);
  const study::ErrorBand band{"CRB 1σ, 3000 samples", fb,
                              fe5::db_crb(fe(), 0.10, 3000, fb, fe5::CrbClass::Reduced)};
  const auto fig = study::comparison_figure(
      in, shown, {band}, "Seed ch. 5 on the FE tube: 10 % noise, 10 MS/s, beta = 1e-7 (seed 1)");
  const auto path = std::filesystem::path(PIEZO_BINARY_DIR) / "chapter5-comparison.svg";
  study::write_comparison_svg(fig, path);
  std::ifstream is(path);
  std::stringstream ss;
  ss << is.rdbuf();
  const std::string svg = ss.str();
  EXPECT_NE(svg.find("<svg"), std::string::npos);
  // The legend's entries are in the figure (Cairo draws text as glyphs: the
  // SVG holds their outlines, not the strings).
  std::string labels;
  for (const auto& p : fig.panels)
    for (const auto& ser : p.series) labels += ser.label + "\n";
  for (const char* label : {"true (FE modal)", "prony (1000)", "prony (3000)", "fft diff (50000)",
                            "CRB 1σ, 3000 samples"})
    EXPECT_NE(labels.find(label), std::string::npos) << label;
  EXPECT_NE(svg.find("<use xlink:href=\"#glyph"), std::string::npos);
  std::printf("figure: %s\n", path.c_str());
}

}  // namespace
