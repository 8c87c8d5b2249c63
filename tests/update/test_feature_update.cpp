// update/feature_update (issue 40): the seed chain's honest status. First the
// status logic against constructed features (no FE): `converged` only when the
// features lie in the band with a sigma, the constants are physical, the
// updated model reproduces the features within their sigma and every constant
// is determined; each refusal names its reason. Then, on the FE model, exact
// features with sigmas (converged, sigmas finite and the truth inside them),
// features outside the band (refused, εT33 still from the capacitance) and a
// single resonance (the stiffness pair not identifiable).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "tests/support/tube_fixture.hpp"
#include "update/feature_update.hpp"

namespace piezo::update {
namespace {

using model::kEps0;
constexpr double kInf = std::numeric_limits<double>::infinity();
const TubeParams kNominal{6.3e10, 0.31, -175e-12, 1576 * kEps0};
const TubeParams kTarget{6.66e10, 0.3333, -190e-12, 1800 * kEps0};

// Features at 51/55/82 kHz (resonances), 52/56/101 kHz (anti-resonances),
// C = 4.5 nF, each with a sigma of 1e-3 relative; the model reproducing them
// with residuals `z` sigmas; constants with 1 % sigmas.
FeatureCheckInput constructed(double z = 0.5) {
  FeatureCheckInput in;
  auto& mf = in.measured;
  mf.resonances_hz = {51400, 55000, 82600};
  mf.antiresonances_hz = {52400, 55800, 101600};
  for (double f : mf.resonances_hz) mf.resonance_sigma_hz.push_back(1e-3 * f);
  for (double f : mf.antiresonances_hz) mf.antiresonance_sigma_hz.push_back(1e-3 * f);
  mf.low_z_hz = 400;
  mf.low_z_ohm = 1 / (2 * M_PI * 400 * 4.5e-9);
  mf.low_z_sigma_ohm = 1e-3 * mf.low_z_ohm;
  in.band = {1e3, 150e3, "test"};
  for (std::size_t i = 0; i < 3; ++i) {
    const double s = i % 2 ? -z : z;
    in.model_resonances_hz.push_back(mf.resonances_hz[i] + s * mf.resonance_sigma_hz[i]);
    in.model_antiresonances_hz.push_back(mf.antiresonances_hz[i] - s * mf.antiresonance_sigma_hz[i]);
  }
  in.model_capacitance_f = 4.5e-9 * (1 + z * 1e-3);
  in.updated = kTarget;
  in.sigma = {0.01 * kTarget.y_e11, 0.01 * kTarget.nu12, 0.01 * std::abs(kTarget.d31), 0.01 * kTarget.eps_t33};
  return in;
}

TEST(FeatureCheck, ConsistentFeaturesConverge) {
  const auto c = check_feature_update(constructed());
  EXPECT_EQ(c.status, "converged") << c.reason;
  EXPECT_EQ(c.dof, 3);
  ASSERT_EQ(c.constants.size(), 4u);
  for (const auto& k : c.constants) EXPECT_EQ(k.status, "ok") << k.name;
  EXPECT_NEAR(c.constants[3].value, 1800, 1e-9);
  EXPECT_NEAR(c.constants[3].sigma, 18, 1e-9);
  EXPECT_EQ(c.birge, 1.0);
}

TEST(FeatureCheck, FeatureOutsideTheBandIsNotConverged) {
  auto in = constructed();
  in.measured.resonances_hz[2] = 960e3;  // what the issue saw: Prony's noise poles at ~1 MHz
  in.measured.resonance_sigma_hz[2] = 500;
  in.model_resonances_hz[2] = 960e3;
  const auto c = check_feature_update(in);
  EXPECT_FALSE(c.converged());
  EXPECT_EQ(c.status, "no_features");
  EXPECT_NE(c.reason.find("outside the band"), std::string::npos) << c.reason;
  for (const auto& k : c.constants) EXPECT_EQ(k.status, "not identifiable") << k.name;
}

TEST(FeatureCheck, FeatureWithoutSigmaIsNotConverged) {
  auto in = constructed();
  in.measured.antiresonance_sigma_hz[1] = NAN;
  const auto c = check_feature_update(in);
  EXPECT_EQ(c.status, "no_features");
  EXPECT_NE(c.reason.find("without a sigma"), std::string::npos) << c.reason;
  auto in2 = constructed();
  in2.measured.low_z_sigma_ohm = 0;
  EXPECT_EQ(check_feature_update(in2).status, "no_features");
}

TEST(FeatureCheck, NoFeaturesAtAll) {
  auto in = constructed();
  in.measured.resonances_hz.clear();
  in.measured.resonance_sigma_hz.clear();
  in.measured.antiresonances_hz.clear();
  in.measured.antiresonance_sigma_hz.clear();
  EXPECT_EQ(check_feature_update(in).status, "no_features");
}

TEST(FeatureCheck, FeaturesNotReproducedAreNotIdentifiable) {
  const auto c = check_feature_update(constructed(4.0));  // every feature 4 sigma off: chi2 112 on 3 dof
  EXPECT_EQ(c.status, "not_identifiable");
  EXPECT_NE(c.reason.find("does not reproduce"), std::string::npos) << c.reason;
  EXPECT_GT(c.chi2, 100);
  EXPECT_LT(c.log10_chance, -3);
}

TEST(FeatureCheck, ModestMisfitWidensTheSigmas) {
  // chi2 = 7 z² on 3 dof: z = 1.2 gives 10.1, chance 0.018 (accepted), Birge ratio 1.83.
  const auto c = check_feature_update(constructed(1.2));
  ASSERT_EQ(c.status, "converged") << c.reason;
  EXPECT_NEAR(c.birge, std::sqrt(7 * 1.44 / 3), 1e-9);
  EXPECT_NEAR(c.constants[0].sigma, c.birge * 0.01 * kTarget.y_e11, 1e-3);
  EXPECT_NEAR(c.constants[0].sigma_statistical, 0.01 * kTarget.y_e11, 1e-3);
}

TEST(FeatureCheck, NonPhysicalConstantsAreRefused) {
  auto in = constructed();
  in.updated.nu12 = 0.62;
  auto c = check_feature_update(in);
  EXPECT_EQ(c.status, "non_physical");
  EXPECT_NE(c.reason.find("nu12"), std::string::npos) << c.reason;
  in = constructed();
  in.updated.d31 = -900e-12;  // k31 = 0.9 sqrt(66.6e9/1.59e-8) ≈ 1.8
  c = check_feature_update(in);
  EXPECT_EQ(c.status, "non_physical");
  EXPECT_NE(c.reason.find("k31"), std::string::npos) << c.reason;
}

TEST(FeatureCheck, UndeterminedConstantIsNotIdentifiable) {
  auto in = constructed();
  in.sigma[1] = kInf;               // nu12: the features leave it open
  in.sigma[2] = 0.2 * 190e-12;      // d31: 20 % relative
  const auto c = check_feature_update(in);
  EXPECT_EQ(c.status, "not_identifiable");
  EXPECT_EQ(c.constants[0].status, "ok");
  EXPECT_EQ(c.constants[1].status, "not identifiable");
  EXPECT_EQ(c.constants[2].status, "not identifiable");
  EXPECT_EQ(c.constants[3].status, "ok");
  EXPECT_NE(c.reason.find("nu12"), std::string::npos) << c.reason;
}

TEST(FeatureCheck, MethodFailureKeepsItsStatus) {
  auto in = constructed();
  in.method_status = "max_iterations";
  in.method_message = "outer sweeps did not settle within 40";
  const auto c = check_feature_update(in);
  EXPECT_EQ(c.status, "max_iterations");
  EXPECT_EQ(c.reason, in.method_message);
}

// On the FE model.
class FeatureUpdateFe : public test::TubeFixture {
 protected:
  MeasuredFeatures exact(const TubeParams& p, double rel_sigma) {
    const auto cls = MaterialClass::isotropic();
    const auto m = cls.e_form(p);
    const auto f = model_frequencies(*solver_, m, 3, 3, CmcmOptions{}.modal);
    MeasuredFeatures mf;
    mf.resonances_hz = f.resonances_hz;
    mf.antiresonances_hz = f.antiresonances_hz;
    for (double x : f.resonances_hz) mf.resonance_sigma_hz.push_back(rel_sigma * x);
    for (double x : f.antiresonances_hz) mf.antiresonance_sigma_hz.push_back(rel_sigma * x);
    mf.low_z_hz = 400;
    mf.low_z_ohm = 1 / (2 * M_PI * 400 * model_capacitance(*solver_, m, 400, CmcmOptions{}.modal));
    mf.low_z_sigma_ohm = 10 * rel_sigma * mf.low_z_ohm;
    return mf;
  }
};

TEST_F(FeatureUpdateFe, ExactFeaturesConvergeWithSigmas) {
  const auto cls = MaterialClass::isotropic();
  const auto mf = exact(kTarget, 2e-4);
  const FeatureBand band{1e3, 200e3, "test"};
  for (auto method : {FeatureMethod::cmcm, FeatureMethod::lm}) {
    const auto u = update_from_features(*tube_, *solver_, cls, kNominal, mf, band, method);
    ASSERT_TRUE(u.ok()) << to_string(method) << ": " << u.check.status << ": " << u.check.reason;
    const double truth[4] = {kTarget.y_e11, kTarget.nu12, kTarget.d31, kTarget.eps_t33 / kEps0};
    for (int k = 0; k < 4; ++k) {
      const auto& c = u.check.constants[static_cast<std::size_t>(k)];
      EXPECT_TRUE(std::isfinite(c.sigma) && c.sigma > 0) << c.name;
      EXPECT_LT(std::abs(c.value - truth[k]), 1e-3 * c.sigma + 1e-6 * std::abs(truth[k])) << c.name;
      std::printf("[%s] %-10s %.6g +- %.3g (%.3g %%)\n", to_string(method), c.name.c_str(), c.value, c.sigma,
                  100 * std::abs(c.sigma / c.value));
    }
    EXPECT_LT(u.check.chi2, 1e-3);
  }
}

TEST_F(FeatureUpdateFe, FeaturesOutsideTheBandAreRefusedButEpsT33Stands) {
  const auto cls = MaterialClass::isotropic();
  auto mf = exact(kTarget, 2e-4);
  const FeatureBand band{1e3, 70e3, "test: the drive covers up to 70 kHz"};
  const auto u = update_from_features(*tube_, *solver_, cls, kNominal, mf, band, FeatureMethod::lm);
  EXPECT_FALSE(u.ok());
  EXPECT_EQ(u.check.status, "no_features");
  EXPECT_NE(u.check.reason.find("outside the band"), std::string::npos) << u.check.reason;
  const auto& e = u.check.constants[3];
  EXPECT_EQ(e.status, "ok") << e.reason;
  // εT33 from C alone, the other constants nominal: within 3 sigma of the truth.
  EXPECT_LT(std::abs(e.value - kTarget.eps_t33 / kEps0), 3 * e.sigma) << e.value << " +- " << e.sigma;
  for (int k = 0; k < 3; ++k) EXPECT_EQ(u.check.constants[static_cast<std::size_t>(k)].status, "not identifiable");

  // No resonance at all: εT33 from the capacitance, status no_features with the caller's reason.
  mf.resonances_hz.clear();
  mf.resonance_sigma_hz.clear();
  mf.antiresonances_hz.clear();
  mf.antiresonance_sigma_hz.clear();
  const auto v = update_from_features(*tube_, *solver_, cls, kNominal, mf, band, FeatureMethod::cmcm,
                                      {}, "no resonance in the drive's band");
  EXPECT_EQ(v.check.status, "no_features");
  EXPECT_EQ(v.check.reason, "no resonance in the drive's band");
  EXPECT_EQ(v.check.constants[3].status, "ok");
  EXPECT_NEAR(v.updated.eps_t33, u.eps_t33_from_c, 1e-12 * u.eps_t33_from_c);
}

TEST_F(FeatureUpdateFe, OneResonanceLeavesTheStiffnessPairOpen) {
  const auto cls = MaterialClass::isotropic();
  auto mf = exact(kTarget, 2e-4);
  mf.resonances_hz.resize(1);
  mf.resonance_sigma_hz.resize(1);
  mf.antiresonances_hz.resize(1);
  mf.antiresonance_sigma_hz.resize(1);
  const FeatureBand band{1e3, 200e3, "test"};
  const auto u = update_from_features(*tube_, *solver_, cls, kNominal, mf, band, FeatureMethod::cmcm);
  EXPECT_FALSE(u.ok());
  EXPECT_EQ(u.check.status, "not_identifiable") << u.check.reason;
}

}  // namespace
}  // namespace piezo::update
