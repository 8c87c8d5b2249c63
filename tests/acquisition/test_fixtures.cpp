// Files written by another tool (h5py, fixtures/make_fixtures.py) read exactly
// like ours: every sample is recomputed here from the same closed forms.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>

#include "acquisition/capture_file.hpp"

using namespace piezo;

namespace {
const std::string kFixtures = std::string(PIEZO_SOURCE_DIR) + "/fixtures/";
constexpr double kR1 = 3140.0, kC0 = 2.1e-9, kFs = 1e7;
}  // namespace

TEST(Fixtures, H5pyExpDecayFloat32) {
  auto cap = acq::read_capture(kFixtures + "h5py-exp-decay.h5");
  EXPECT_EQ(cap.setup.divider_r1_ohm, kR1);
  EXPECT_EQ(cap.setup.transducer_id, "fixture-rc");
  EXPECT_FALSE(cap.setup.inner_diameter_m.has_value());
  EXPECT_EQ(cap.setup.geometry().inner_diameter_m, 0.016);  // project default
  ASSERT_EQ(cap.shots.size(), 1u);
  const auto& s = cap.shots[0];
  EXPECT_EQ(s.excitation, acq::Excitation::ExpDecay);
  EXPECT_EQ(s.amplitude_v, 1.0);
  EXPECT_EQ(s.decay_per_s, 3000.0);
  EXPECT_EQ(s.pretrigger_samples, 100);
  EXPECT_EQ(s.role, acq::Role::Dut);
  ASSERT_EQ(s.samples(), 4000u);
  const double tau = kR1 * kC0;
  for (std::size_t i = 0; i < s.samples(); ++i) {
    double t = (static_cast<double>(i) - 100.0) / kFs;
    double v1 = t >= 0 ? std::exp(-3000.0 * t) : 0.0;
    double v2 = t >= 0 ? 1.0 / (1 - 3000.0 * tau) * (std::exp(-3000.0 * t) - std::exp(-t / tau))
                       : 0.0;
    // stored as float32: the reader must return exactly the float-rounded value
    // (the closed form in numpy and here may differ in the last double ulp).
    ASSERT_NEAR(s.v1[i], v1, 1e-7) << i;
    ASSERT_NEAR(s.v2[i], v2, 1e-7) << i;
    ASSERT_EQ(s.v1[i], static_cast<double>(static_cast<float>(s.v1[i])));
  }
}

TEST(Fixtures, H5pySineWithCalibrationShotsFixedLengthStrings) {
  auto cap = acq::read_capture(kFixtures + "h5py-sine-cal.h5");
  EXPECT_EQ(cap.created_utc, "2026-11-21T12:00:00Z");
  EXPECT_EQ(cap.setup.material, "apc850");
  EXPECT_EQ(cap.setup.length_m, 0.020);
  ASSERT_EQ(cap.shots.size(), 4u);
  const acq::Role roles[] = {acq::Role::Dut, acq::Role::Open, acq::Role::Short, acq::Role::Load};
  const double w = 2 * M_PI * 50e3;
  const std::complex<double> z[] = {1.0 / std::complex<double>(0, w * kC0),
                                    1.0 / std::complex<double>(0, w * 100e-12), {0.5, 0}, {1000, 0}};
  for (int k = 0; k < 4; ++k) {
    const auto& s = cap.shots[k];
    EXPECT_EQ(s.role, roles[k]);
    EXPECT_EQ(s.excitation, acq::Excitation::Sine);
    EXPECT_EQ(s.frequency_hz, 50e3);
    auto h = z[k] / (z[k] + kR1);
    for (std::size_t i = 0; i < s.samples(); i += 37) {
      double t = i / kFs;
      ASSERT_NEAR(s.v1[i], std::sin(w * t), 1e-12);
      ASSERT_NEAR(s.v2[i], std::abs(h) * std::sin(w * t + std::arg(h)), 1e-12);
    }
  }
  EXPECT_EQ(cap.shots[3].load_ohm, 1000.0);
  EXPECT_EQ(cap.shots[3].load_parallel_f, 0.0);
}
