// update/least_squares: Levenberg–Marquardt as the second, independent
// updater; agreement with CMCM (the acceptance's second-method check).
#include <gtest/gtest.h>

#include <cstdio>

#include "update/least_squares.hpp"
#include "update/updater.hpp"
#include "tests/support/tube_fixture.hpp"

namespace piezo::update {
namespace {

using model::kEps0;
const TubeParams kOriginal{6.3e10, 0.31, -175e-12, 1576 * kEps0};
const TubeParams kTarget{6.66e10, 0.3333, -210e-12, 2294 * kEps0};

class LeastSquares : public test::TubeFixture {
 protected:
};

MeasuredFeatures published() {
  MeasuredFeatures mf;
  mf.resonances_hz = {51400, 55000, 82600};
  mf.antiresonances_hz = {52400, 55800, 101600};
  mf.low_z_ohm = 26804;
  mf.low_z_hz = 400;
  return mf;
}

double max_rel_diff(const TubeParams& a, const TubeParams& b) {
  return std::max({std::abs(a.y_e11 / b.y_e11 - 1), std::abs(a.nu12 / b.nu12 - 1),
                   std::abs(a.d31 / b.d31 - 1), std::abs(a.eps_t33 / b.eps_t33 - 1)});
}

void print(const char* what, const TubeParams& c, const TubeParams& l, double t_c, double t_l,
           int it_l) {
  std::printf(
      "[%s] CMCM vs LM: YE11 %.6g / %.6g, nu12 %.6f / %.6f, d31 %.5g / %.5g, "
      "epsT33 %.2f / %.2f eps0; max rel diff %.2e; %.3f s / %.3f s (LM %d iterations)\n",
      what, c.y_e11, l.y_e11, c.nu12, l.nu12, c.d31, l.d31, c.eps_t33 / kEps0, l.eps_t33 / kEps0,
      max_rel_diff(c, l), t_c, t_l, it_l);
}

// Inverse crime: both must land on the target, so they agree to 1e-6
// (each converged to ≲1e-7; see test_update_tube.cpp for the CMCM bound).
TEST_F(LeastSquares, InverseCrimeAgreesWithCmcmAndTarget) {
  const auto cls = MaterialClass::isotropic();
  const auto m = cls.e_form(kTarget);
  const auto f = model_frequencies(*solver_, m, 3, 3, CmcmOptions{}.modal);
  MeasuredFeatures mf;
  mf.resonances_hz = f.resonances_hz;
  mf.antiresonances_hz = f.antiresonances_hz;
  mf.low_z_hz = 400;
  mf.low_z_ohm = 1 / (2 * M_PI * 400 * model_capacitance(*solver_, m, 400, CmcmOptions{}.modal));
  const auto lm = update_lm(*tube_, *solver_, cls, kOriginal, mf);
  ASSERT_TRUE(lm.ok()) << lm.message;
  const auto cm = update_cmcm(*tube_, *solver_, cls, kOriginal, mf);
  ASSERT_TRUE(cm.ok()) << cm.message;
  print("inverse crime", cm.updated, lm.updated, cm.seconds, lm.seconds, lm.iterations);
  EXPECT_LT(max_rel_diff(lm.updated, kTarget), 1e-6);
  EXPECT_LT(max_rel_diff(lm.updated, cm.updated), 1e-6);
  EXPECT_LT(lm.cost, 1e-20);
}

// Published (inconsistent) features: the two methods minimise different
// things (CMCM: the resonances with the stiffnesses only, then the
// anti-resonances with a only, capacitance matched exactly; LM: all seven
// relative errors with all four parameters at once), so they need not
// coincide. Measured spread: 0.45 % (isotropic) and 0.55 % (transversely
// isotropic), in nu12/YE11, the least-determined pair; held to 1 %.
TEST_F(LeastSquares, PublishedFeaturesAgreeWithCmcmWithinTheDiscrepancy) {
  const auto cls = MaterialClass::isotropic();
  const auto lm = update_lm(*tube_, *solver_, cls, kOriginal, published());
  ASSERT_TRUE(lm.ok()) << lm.message;
  const auto cm = update_cmcm(*tube_, *solver_, cls, kOriginal, published());
  ASSERT_TRUE(cm.ok()) << cm.message;
  print("published", cm.updated, lm.updated, cm.seconds, lm.seconds, lm.iterations);
  EXPECT_LT(max_rel_diff(lm.updated, cm.updated), 1e-2);
  EXPECT_LT(max_rel_diff(lm.updated, kTarget), 1e-2);
}

TEST_F(LeastSquares, TransverselyIsotropicClassConverges) {
  model::PiezoMaterialD n;
  n.s_e13 = -5.74e-12;
  n.s_e33 = 18.5e-12;
  n.s_e44 = 46e-12;
  n.d33 = 400e-12;
  n.d15 = 590e-12;
  n.eps_t11 = 1851 * kEps0;
  const auto cls = MaterialClass::transversely_isotropic(n);
  const auto lm = update_lm(*tube_, *solver_, cls, kOriginal, published());
  ASSERT_TRUE(lm.ok()) << lm.message;
  const auto cm = update_cmcm(*tube_, *solver_, cls, kOriginal, published());
  ASSERT_TRUE(cm.ok()) << cm.message;
  print("published, transversely isotropic", cm.updated, lm.updated, cm.seconds, lm.seconds,
        lm.iterations);
  EXPECT_LT(max_rel_diff(lm.updated, cm.updated), 1e-2);
}

TEST_F(LeastSquares, IterationCapIsAStatus) {
  LmOptions o;
  o.max_iterations = 1;
  const auto lm =
      update_lm(*tube_, *solver_, MaterialClass::isotropic(), kOriginal, published(), o);
  EXPECT_EQ(lm.status, UpdateStatus::max_iterations);
  EXPECT_FALSE(lm.message.empty());
}

}  // namespace
}  // namespace piezo::update
