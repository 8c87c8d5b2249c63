// Coverage of the uncertainty band (issue 10): over noise seeds, at how many
// frequencies (1–120 kHz, away from the peaks) does the 95 % band of the
// compensated Prony estimate (bootstrap over 8 shots + fixture standards +
// model order) contain the true transducer impedance, |Z| and phase both?
// Target: >= 90 %. PIEZO_COVERAGE_SEEDS = 2 in CI, 50 in `make validate`.
//
// Measured: 93.2 % over 50 seeds, 100 % on the 2 CI seeds — the target is met
// since the calibration standards' FFT ratio takes the record's last sample
// from a fit (FftRatioOptions::end_fit_samples): its noise, common to every
// bin, made a compensation error of up to 0.2 % / 0.1° at 1–20 kHz that the
// standards' σ did not hold. The test holds the target; docs/dsp-methods.md quotes
// the numbers.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <vector>

#include "acquisition/impedance_assessment.hpp"
#include "fixture_study.hpp"
#include "tests/support/sim_truth.hpp"

namespace {
using namespace piezo;
namespace fs = std::filesystem;

// One source, two programs: distinct suite names, or CTest (which keys test
// properties by name) gives the CI program the validate program's label and
// `make test` skips it.
#if PIEZO_COVERAGE_SEEDS > 2
#define PIEZO_COVERAGE_SUITE UncertaintyCoverageValidate
#else
#define PIEZO_COVERAGE_SUITE UncertaintyCoverage
#endif
TEST(PIEZO_COVERAGE_SUITE, BandCoversTheTruth) {
  const test::FixtureSetting s{"150pF_10ohm_R1+3pct_skew173ns", 150e-12, 10.0, 0.03, 173e-9};
  const auto dir =
      fs::temp_directory_path() / ("piezobench-coverage-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::size_t covered = 0, points = 0, covered_mag = 0, covered_phase = 0;
  double worst = 1.0;
  std::vector<double> width;  // full relative width of the |Z| band, 2·k·σ/|Z|, in %
  for (int seed = 1; seed <= PIEZO_COVERAGE_SEEDS; ++seed) {
    const auto spec = test::fixture_spec(s, static_cast<std::uint64_t>(seed));
    const auto cap = test::measure_capture(spec, 8, true, dir / "c.h5");
    acq::AssessmentOptions o;
    o.fmin_hz = 1e3;
    o.fmax_hz = 120e3;
    o.step_hz = 500.0;
    o.prony.prep.max_samples = 6000;
    o.uncertainty = acq::UncertaintySource::Shots;
    o.bootstrap = 30;
    o.seed = 100 + static_cast<std::uint64_t>(seed);
    o.validity = false;
    o.stabilization = false;
    o.kk = false;
    const auto a = acq::assess_impedance(cap, o);
    ASSERT_TRUE(a.band);
    const auto truth = test::true_tube_impedance(spec);
    const auto peaks = test::true_peaks(truth, 120e3);
    std::size_t in = 0, n = 0;
    for (Eigen::Index k = 0; k < a.band->size(); ++k) {
      const double f = a.band->f_hz[k];
      if (test::near_peak(f, peaks)) continue;
      const auto zt = truth(f);
      const bool c = a.band->covers(k, zt);
      in += c;
      ++n;
      const double k95 = a.band->coverage_factor;
      width.push_back(200.0 * k95 * a.band->abs_sigma_ohm[k] / a.band->abs_ohm[k]);
      covered_mag += std::abs(std::abs(zt) - a.band->abs_ohm[k]) <= k95 * a.band->abs_sigma_ohm[k];
      covered_phase += std::abs(std::remainder(std::arg(zt) - a.band->phase_rad[k], 2 * M_PI)) <=
                       k95 * a.band->phase_sigma_rad[k];
    }
    covered += in;
    points += n;
    worst = std::min(worst, double(in) / double(n));
    std::printf("seed %d: coverage %.1f %% (%zu of %zu frequencies), band: %s\n", seed,
                100.0 * in / n, in, n, a.band->source.c_str());
  }
  const double cov = double(covered) / double(points);
  std::nth_element(width.begin(), width.begin() + width.size() / 2, width.end());
  std::printf(
      "coverage over %d seeds: %.1f %% (|Z| alone %.1f %%, phase alone %.1f %%), worst seed %.1f "
      "%% (target >= 90 %%); median |Z| band width %.2f %% of |Z|\n",
      PIEZO_COVERAGE_SEEDS, 100 * cov, 100.0 * covered_mag / points, 100.0 * covered_phase / points,
      100 * worst, width[width.size() / 2]);
  // The line held is the target. 50 seeds: 93.2 % (|Z| 97.3 %, phase 95.5 %,
  // worst seed 75.3 %); 82.7 % with the standards' last sample as recorded,
  // 73.3 % with Prony's pole model from t = 0 as well (its truncation bias next
  // to the 82 kHz resonance; PronyImpedanceOptions::direct_samples), 27.7 %
  // without the drive's ramp from −Δt. The 2 CI seeds: 100 % (80.2 % and
  // 79.5 % in those earlier states).
  EXPECT_GE(cov, 0.90);
  fs::remove_all(dir);
}

}  // namespace
