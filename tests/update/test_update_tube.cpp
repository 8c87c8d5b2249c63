// update/updater + extended CMCM on the FE tube: seed chapter 7 (Tables 4/5),
// the "inverse crime" on our own FE frequencies, both model classes, and the
// failure statuses (non-convergence, ambiguous pairing, too few modes,
// non-physical iterate).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "update/updater.hpp"
#include "tests/support/tube_fixture.hpp"

namespace piezo::update {
namespace {

using model::kEps0;

const TubeParams kOriginal{6.3e10, 0.31, -175e-12, 1576 * kEps0};  // Table 4
const TubeParams kTarget{6.66e10, 0.3333, -210e-12, 2294 * kEps0};

model::PiezoMaterialD apc850_insensitive() {
  model::PiezoMaterialD n;  // Table 2 values of the six insensitive constants
  n.s_e13 = -5.74e-12;
  n.s_e33 = 18.5e-12;
  n.s_e44 = 46e-12;
  n.d33 = 400e-12;
  n.d15 = 590e-12;
  n.eps_t11 = 1851 * kEps0;
  return n;
}

class TubeUpdate : public test::TubeFixture {
 protected:
  // Features of our own FE model of `p` (the inverse crime).
  static MeasuredFeatures own_features(const MaterialClass& cls, const TubeParams& p) {
    const auto m = cls.e_form(p);
    const auto f = model_frequencies(*solver_, m, 3, 3, CmcmOptions{}.modal);
    MeasuredFeatures mf;
    mf.resonances_hz = f.resonances_hz;
    mf.antiresonances_hz = f.antiresonances_hz;
    mf.low_z_hz = 400;
    mf.low_z_ohm =
        1.0 / (2 * M_PI * 400 * model_capacitance(*solver_, m, 400, CmcmOptions{}.modal));
    return mf;
  }
  static MeasuredFeatures published() {
    MeasuredFeatures mf;  // Table 4/5 target features (ANSYS, 3 digits)
    mf.resonances_hz = {51400, 55000, 82600};
    mf.antiresonances_hz = {52400, 55800, 101600};
    mf.low_z_ohm = 26804;
    mf.low_z_hz = 400;
    return mf;
  }
  static double rel(double a, double b) { return a / b - 1.0; }
  static void report(const char* what, const UpdateResult& r) {
    std::printf(
        "[%s] %s: YE11 %+.4f%% nu12 %+.4f%% d31 %+.4f%% epsT33 %+.4f%% | a1 %.4f a2 %.4f a3 %.4f | "
        "iterations elastic %d piezo %d (first sweep %d/%d), sweeps %d, %.3f s\n",
        what, to_string(r.status), 100 * rel(r.updated.y_e11, kTarget.y_e11),
        100 * rel(r.updated.nu12, kTarget.nu12), 100 * rel(r.updated.d31, kTarget.d31),
        100 * rel(r.updated.eps_t33, kTarget.eps_t33), r.alpha1, r.alpha2, r.alpha3,
        r.iterations_elastic, r.iterations_piezo, r.elastic_per_sweep.front(),
        r.piezo_per_sweep.front(), r.sweeps, r.seconds);
  }
};

// Inverse crime, isotropic class: the features come from this FE model, so the
// target is a fixed point and must be recovered to the iteration tolerances
// (CMCM |Δα| < 1e-9, sweeps 1e-8; conditioning of nu12 from three frequencies
// ~1e2) → 1e-6 relative.
TEST_F(TubeUpdate, InverseCrimeIsotropicRecoversTheTarget) {
  const auto cls = MaterialClass::isotropic();
  const auto r = update_cmcm(*tube_, *solver_, cls, kOriginal, own_features(cls, kTarget));
  report("inverse crime, isotropic", r);
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_NEAR(rel(r.updated.y_e11, kTarget.y_e11), 0, 1e-6);
  EXPECT_NEAR(rel(r.updated.nu12, kTarget.nu12), 0, 1e-6);
  EXPECT_NEAR(rel(r.updated.d31, kTarget.d31), 0, 1e-6);
  EXPECT_NEAR(rel(r.updated.eps_t33, kTarget.eps_t33), 0, 1e-6);
  // The α's are then those of the exact target coordinates.
  const auto q0 = cls.coordinates(kOriginal), qt = cls.coordinates(kTarget);
  EXPECT_NEAR(r.alpha1, qt.c1 / q0.c1 - 1, 1e-6);
  EXPECT_NEAR(r.alpha2, qt.c2 / q0.c2 - 1, 1e-6);
}

TEST_F(TubeUpdate, InverseCrimeTransverselyIsotropicRecoversTheTarget) {
  const auto cls = MaterialClass::transversely_isotropic(apc850_insensitive());
  const auto r = update_cmcm(*tube_, *solver_, cls, kOriginal, own_features(cls, kTarget));
  report("inverse crime, transversely isotropic", r);
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_NEAR(rel(r.updated.y_e11, kTarget.y_e11), 0, 1e-6);
  EXPECT_NEAR(rel(r.updated.nu12, kTarget.nu12), 0, 1e-6);
  EXPECT_NEAR(rel(r.updated.d31, kTarget.d31), 0, 1e-6);
  EXPECT_NEAR(rel(r.updated.eps_t33, kTarget.eps_t33), 0, 1e-6);
}

// Tables 4/5 from the published (ANSYS 3-D, 3-digit) target features. Our
// axisymmetric FE model of the target material is 0.07-0.24 % away from those
// frequencies, so this is a model-discrepancy test, not a fixed point:
// YE11, d31 and εT33 within the 0.1 % goal; nu12 (the worst-conditioned
// parameter from three resonances) comes out 0.60 % high and is held to 1 %.
TEST_F(TubeUpdate, PublishedTable45Features) {
  const auto r = update_cmcm(*tube_, *solver_, MaterialClass::isotropic(), kOriginal, published());
  report("published Table 4/5, isotropic", r);
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_NEAR(rel(r.updated.y_e11, kTarget.y_e11), 0, 1e-3);
  EXPECT_NEAR(rel(r.updated.d31, kTarget.d31), 0, 1e-3);
  EXPECT_NEAR(rel(r.updated.eps_t33, kTarget.eps_t33), 0, 1e-3);
  EXPECT_NEAR(rel(r.updated.nu12, kTarget.nu12), 0, 1e-2);
  // The seed's α's (0.1455, 0.2755, −0.0315) within the same discrepancy.
  EXPECT_NEAR(r.alpha1, 0.1455, 0.01);
  EXPECT_NEAR(r.alpha2, 0.2755, 0.025);
  EXPECT_NEAR(r.alpha3, -0.0315, 0.002);
  // The updated model reproduces the measured resonances to the discrepancy level.
  for (int j = 0; j < 3; ++j)
    EXPECT_NEAR(rel(r.model_resonances_hz[j], published().resonances_hz[j]), 0, 1e-3);
}

// The seed's own procedure (issue 44 item 4): one pass, i != j equations. On
// its own exact features (the inverse crime: the target is a fixed point of
// every phase) it still misses the target, because our short-circuit
// resonances depend on a = e31²/εS33 (the internal potentials are condensed)
// and one pass fits c1, c2 with the original a; the outer sweeps recover it.
// The histories hold every iteration (Figs 36-37).
TEST_F(TubeUpdate, SeedProcedureIsOnePassAndMissesItsOwnTarget) {
  const auto cls = MaterialClass::isotropic();
  const auto q0 = cls.coordinates(kOriginal), qt = cls.coordinates(kTarget);
  const double a1 = qt.c1 / q0.c1 - 1, a2 = qt.c2 / q0.c2 - 1;  // the target's α1, α2
  UpdateOptions seed;
  seed.seed_procedure = true;
  seed.cmcm.cross_modes = true;
  const auto s = update_cmcm(*tube_, *solver_, cls, kOriginal, own_features(cls, kTarget), seed);
  std::printf("[seed procedure, own features] %s: a1 %.5f (target %.5f) a2 %.5f (target %.5f), iterations %d/%d: %s\n",
              to_string(s.status), s.alpha1, a1, s.alpha2, a2, s.iterations_elastic, s.iterations_piezo,
              s.message.c_str());
  EXPECT_EQ(s.sweeps, 1);
  EXPECT_EQ(s.elastic_alpha_history.size(), static_cast<std::size_t>(s.iterations_elastic));
  EXPECT_EQ(s.piezo_alpha_history.size(), static_cast<std::size_t>(s.iterations_piezo));
  EXPECT_GT(std::abs(s.alpha1 / a1 - 1), 0.01);  // one pass: off by more than 1 %
  UpdateOptions sweeps;
  sweeps.cmcm.cross_modes = true;
  const auto w = update_cmcm(*tube_, *solver_, cls, kOriginal, own_features(cls, kTarget), sweeps);
  ASSERT_TRUE(w.ok()) << w.message;
  EXPECT_NEAR(w.alpha1 / a1 - 1, 0, 1e-4);
  EXPECT_NEAR(w.alpha2 / a2 - 1, 0, 1e-4);
  ASSERT_FALSE(w.elastic_alpha_history.empty());
  EXPECT_DOUBLE_EQ(w.elastic_alpha_history.back()[0], w.alpha1);  // the last iterate is the answer
}

TEST_F(TubeUpdate, AnalyticCapacitanceOptionUsesEq201) {
  UpdateOptions o;
  o.capacitance = CapacitanceModel::analytic;
  const auto r =
      update_cmcm(*tube_, *solver_, MaterialClass::isotropic(), kOriginal, published(), o);
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_DOUBLE_EQ(r.updated.eps_t33, r.eps_t33_eq201);
  EXPECT_NEAR(rel(r.updated.eps_t33, kTarget.eps_t33), 0, 1e-3);
}

// A single extended-CMCM pass (phase 1 at full tolerance) against the seed's 14.
TEST_F(TubeUpdate, SinglePassIterationCountsAndCrossModeCreep) {
  const auto cls = MaterialClass::isotropic();
  const auto q = cls.coordinates(kOriginal);
  CmcmPhase p;
  p.name = "elastic";
  p.theta0 = {q.c1, q.c2};
  p.measured_hz = own_features(cls, kTarget).resonances_hz;
  p.material = [&](std::span<const double> th) {
    Coordinates c = q;
    c.c1 = th[0];
    c.c2 = th[1];
    return cls.e_form(cls.params(c));
  };
  const auto diag = extended_cmcm(*tube_, *solver_, p);
  ASSERT_TRUE(diag.ok()) << diag.message;
  EXPECT_LE(diag.iterations, 20);
  CmcmOptions cross;
  cross.cross_modes = true;
  cross.max_iterations = 100;
  const auto creep = extended_cmcm(*tube_, *solver_, p, cross);
  std::printf(
      "[single pass, elastic] diagonal equations: %d iterations, alpha %.6f %.6f; with "
      "cross-mode equations: %s after %d, alpha %.6f %.6f\n",
      diag.iterations, diag.alpha[0], diag.alpha[1], to_string(creep.status), creep.iterations,
      creep.alpha[0], creep.alpha[1]);
  EXPECT_EQ(creep.status, UpdateStatus::max_iterations);
  EXPECT_FALSE(creep.message.empty());
  EXPECT_GT(std::abs(creep.alpha[0] - diag.alpha[0]), 1e-4);  // still creeping
}

TEST_F(TubeUpdate, IterationCapIsAStatusWithAMessage) {
  UpdateOptions o;
  o.cmcm.max_iterations = 2;
  o.cmcm.tolerance = 1e-14;
  const auto r =
      update_cmcm(*tube_, *solver_, MaterialClass::isotropic(), kOriginal, published(), o);
  EXPECT_EQ(r.status, UpdateStatus::max_iterations);
  EXPECT_NE(r.message.find("not converged"), std::string::npos) << r.message;
}

TEST_F(TubeUpdate, AmbiguousPairingIsReported) {
  UpdateOptions o;
  o.cmcm.mac_min = 0.9;
  o.cmcm.mac_margin = 1.0;  // no mode can beat its runner-up by a full unit of MAC
  const auto r =
      update_cmcm(*tube_, *solver_, MaterialClass::isotropic(), kOriginal, published(), o);
  EXPECT_EQ(r.status, UpdateStatus::ambiguous_pairing);
  EXPECT_NE(r.message.find("ambiguous pairing"), std::string::npos) << r.message;
}

TEST_F(TubeUpdate, TooFewActiveModesIsReported) {
  UpdateOptions o;
  o.cmcm.modal.n_modes = 3;  // rigid + 2 elastic modes: at most one active
  const auto r =
      update_cmcm(*tube_, *solver_, MaterialClass::isotropic(), kOriginal, published(), o);
  EXPECT_EQ(r.status, UpdateStatus::too_few_modes);
  EXPECT_NE(r.message.find("electrically active"), std::string::npos) << r.message;
}

// Anti-resonances BELOW the resonances would need a < 0 (negative coupling
// energy): the iterate leaves the physical domain and the update stops.
TEST_F(TubeUpdate, NonPhysicalTargetIsRefused) {
  auto f = published();
  f.antiresonances_hz = {45000, 50000, 70000};
  const auto r = update_cmcm(*tube_, *solver_, MaterialClass::isotropic(), kOriginal, f);
  EXPECT_FALSE(r.ok());
  // Refused either way: out of the physical domain, an ambiguous pairing, or
  // (since CMCM halves steps that leave the domain) a coupling driven to zero,
  // which leaves no electrically active mode to pair.
  EXPECT_TRUE(r.status == UpdateStatus::non_physical || r.status == UpdateStatus::ambiguous_pairing ||
              r.status == UpdateStatus::too_few_modes)
      << to_string(r.status) << ": " << r.message;
  EXPECT_FALSE(r.message.empty());
}

TEST_F(TubeUpdate, BadFeaturesThrow) {
  auto f = published();
  f.resonances_hz = {55000, 51400, 82600};
  EXPECT_THROW(update_cmcm(*tube_, *solver_, MaterialClass::isotropic(), kOriginal, f),
               std::invalid_argument);
  f = published();
  f.low_z_hz = 60000;
  EXPECT_THROW(update_cmcm(*tube_, *solver_, MaterialClass::isotropic(), kOriginal, f),
               std::invalid_argument);
}

}  // namespace
}  // namespace piezo::update
