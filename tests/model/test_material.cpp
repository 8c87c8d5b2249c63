// Materials: exact d↔e conversions (seed eqs 8-12), the isotropic class of
// §6.4.3 against the numbers printed in seed ch. 7, presets, validation.
#include <gtest/gtest.h>

#include <Eigen/LU>
#include <cmath>

#include "model/material.hpp"
#include "model/material_presets.hpp"

using namespace piezo::model;

namespace {
double rel(double a, double b) { return std::abs(a - b) / std::abs(b); }
}  // namespace

TEST(Material, DToEToDRoundTripIsExact) {
  // Tolerance 1e-12: two 6×6 inversions of a matrix with condition ~10 in double.
  for (const auto& p : material_presets()) {
    const auto e = to_e_form(p.material);
    const auto d = to_d_form(e);
    EXPECT_LT(rel(d.s_e11, p.material.s_e11), 1e-12) << p.name;
    EXPECT_LT(rel(d.s_e12, p.material.s_e12), 1e-12) << p.name;
    EXPECT_LT(rel(d.s_e13, p.material.s_e13), 1e-12) << p.name;
    EXPECT_LT(rel(d.s_e33, p.material.s_e33), 1e-12) << p.name;
    EXPECT_LT(rel(d.s_e44, p.material.s_e44), 1e-12) << p.name;
    EXPECT_LT(rel(d.d31, p.material.d31), 1e-12) << p.name;
    EXPECT_LT(rel(d.d33, p.material.d33), 1e-12) << p.name;
    EXPECT_LT(rel(d.d15, p.material.d15), 1e-12) << p.name;
    EXPECT_LT(rel(d.eps_t11, p.material.eps_t11), 1e-12) << p.name;
    EXPECT_LT(rel(d.eps_t33, p.material.eps_t33), 1e-12) << p.name;
  }
}

TEST(Material, EFormSatisfiesDefiningRelations) {
  const auto& d = find_preset("apc850").material;
  const auto e = to_e_form(d);
  const auto dm = to_matrices(d), em = to_matrices(e);
  // cE·sE = I (eq. 8), e = d·cE (eq. 9), epsS = epsT − d cE dᵀ (eq. 11), = epsT − e dᵀ (eq. 10).
  EXPECT_LT((em.elastic * dm.elastic - Eigen::Matrix<double, 6, 6>::Identity()).norm(), 1e-12);
  EXPECT_LT((em.piezo - dm.piezo * em.elastic).norm() / em.piezo.norm(), 1e-12);
  const Eigen::Matrix3d eps_s = dm.dielectric - em.piezo * dm.piezo.transpose();
  EXPECT_LT((em.dielectric - eps_s).norm() / eps_s.norm(), 1e-12);
  // cE66 = (cE11 − cE12)/2 is consistent with sE66 = 2(sE11 − sE12).
  EXPECT_LT(rel(em.elastic(5, 5), 1.0 / dm.elastic(5, 5)), 1e-12);
}

TEST(Material, IsotropicClassMatchesSeedChapter7Numbers) {
  // Seed p.104: YE11 = 6.3e10, nu12 = 0.31 → cE11 = cE33 = 8.73e10, cE12 = cE13 = 3.92e10,
  // cE44 = cE66 = 2.415e10 (printed to 3-4 digits → tolerance 0.1 %). The printed cE44
  // is a slip of the seed: YE11/(2(1 + nu12)) = 6.3e10/2.62 = 2.4046e10 (eq. 224).
  IsotropicPiezoParams orig{6.3e10, 0.31, -175e-12, 1576 * kEps0};
  auto e = to_e_form(to_d_form(orig));
  EXPECT_LT(rel(e.c_e11, 8.73e10), 1e-3);
  EXPECT_LT(rel(e.c_e33, e.c_e11), 1e-12);
  EXPECT_LT(rel(e.c_e12, 3.92e10), 1e-3);
  EXPECT_LT(rel(e.c_e13, e.c_e12), 1e-12);
  EXPECT_LT(rel(e.c_e44, 6.3e10 / 2.62), 1e-12);
  EXPECT_LT(rel(e.c_e44, 2.415e10), 5e-3);
  EXPECT_LT(rel(e.c_e44, 0.5 * (e.c_e11 - e.c_e12)), 1e-12);  // eq. 235
  EXPECT_EQ(e.e15, 0.0);
  EXPECT_EQ(e.eps_s11, 0.0);  // epsT11 = d15 = 0 → epsS11 = 0 exactly
  // Eqs 228, 229, 233 hold exactly for the class.
  EXPECT_LT(rel(e.e31, orig.d31 * (e.c_e11 + e.c_e12)), 1e-12);
  EXPECT_LT(rel(e.e33, 2 * orig.d31 * e.c_e12), 1e-12);
  EXPECT_LT(rel(e.eps_s33, orig.eps_t33 - 2 * orig.d31 * orig.d31 * (e.c_e11 + e.c_e12)), 1e-12);

  // Seed p.105-106 (target elastic constants, original d31/epsT33): cE11* = 10e10,
  // cE12* = 5.0004e10, e31 = −26.25, epsS33 = 538 eps0. Those are the CMCM-updated,
  // rounded constants; the exact ones from (6.66e10, 0.3333) are 0.12 % lower, which
  // moves epsS33 = epsT33 − 2 d31²(cE11 + cE12) by 0.3 % → tolerance 5e-3.
  IsotropicPiezoParams mixed{6.66e10, 0.3333, -175e-12, 1576 * kEps0};
  auto m = to_e_form(to_d_form(mixed));
  EXPECT_LT(rel(m.c_e11, 10.0e10), 2e-3);
  EXPECT_LT(rel(m.c_e12, 5.0004e10), 2e-3);
  EXPECT_LT(rel(m.e31, -26.25), 2e-3);
  EXPECT_LT(rel(m.eps_s33 / kEps0, 538), 5e-3);
  // Published updated target: epsS33 = 800 eps0, e31 = −31.5 (table4_5 "published_updated").
  auto t = to_e_form(to_d_form(IsotropicPiezoParams{6.66e10, 0.3333, -210e-12, 2294 * kEps0}));
  EXPECT_LT(rel(t.eps_s33 / kEps0, 800), 5e-3);
  EXPECT_LT(rel(t.e31, -31.5), 5e-3);
}

TEST(Material, IsotropicParamsRoundTrip) {
  IsotropicPiezoParams p{6.66e10, 0.3333, -210e-12, 2294 * kEps0};
  auto q = isotropic_params(to_d_form(p));
  EXPECT_LT(rel(q.y_e11, p.y_e11), 1e-14);
  EXPECT_LT(rel(q.nu12, p.nu12), 1e-14);
  EXPECT_EQ(q.d31, p.d31);
  EXPECT_EQ(q.eps_t33, p.eps_t33);
}

TEST(Material, EngineeringConstantsRoundTrip) {
  const auto& d = find_preset("pzt4").material;
  auto ec = engineering_constants(d);
  EXPECT_LT(rel(ec.y_e11, 1.0 / 12.3e-12), 1e-14);
  EXPECT_LT(rel(ec.nu12, 4.05 / 12.3), 1e-14);
  auto back = with_engineering_constants(d, ec);
  EXPECT_LT(rel(back.s_e13, d.s_e13), 1e-14);
  EXPECT_LT(rel(back.s_e44, d.s_e44), 1e-14);
}

TEST(Material, PresetsArePhysical) {
  ASSERT_GE(material_presets().size(), 4u);
  for (const char* name : {"apc850", "PZT-4", "pzt_8", "PZT5H"}) {
    const auto& p = find_preset(name);
    EXPECT_GT(p.density_kg_m3, 7000) << name;
    auto e = to_e_form(p.material);  // throws if not positive definite
    EXPECT_NO_THROW(validate(e, "test"));
    EXPECT_GT(e.eps_s11, 0);
    EXPECT_LT(e.eps_s33, p.material.eps_t33);  // clamping lowers the permittivity
    EXPECT_LT(e.e31, 0);
    EXPECT_GT(e.e33, 0);
  }
  EXPECT_EQ(find_preset("apc850").density_kg_m3, 7600.0);  // seed Table 2 model
  EXPECT_DOUBLE_EQ(find_preset("apc850").material.s_e44, 46e-12);
}

TEST(Material, PreconditionsThrowWithFunctionName) {
  try {
    find_preset("unobtainium");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("find_preset"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("apc850"), std::string::npos);
  }
  PiezoMaterialD bad = find_preset("apc850").material;
  bad.s_e12 = -bad.s_e11;  // singular compliance
  EXPECT_THROW(to_e_form(bad), std::invalid_argument);
  PiezoMaterialD overcoupled = find_preset("apc850").material;
  overcoupled.d31 *= 5;  // k31 > 1 → negative epsS33
  EXPECT_THROW(to_e_form(overcoupled), std::invalid_argument);
  EXPECT_THROW(to_d_form(IsotropicPiezoParams{6e10, 0.6, -1e-10, 1e-8}), std::invalid_argument);
  PiezoMaterialE e = to_e_form(find_preset("apc850").material);
  e.eps_s33 = 0;
  EXPECT_THROW(validate(e, "caller"), std::invalid_argument);
  MaterialLosses l;
  l.qm = -1;
  EXPECT_THROW(l.validate(), std::invalid_argument);
}

// Seed eqs 106-110: the axisymmetric element's e-form from the REDUCED d-form
// (strains S1, S2, S3, S5 and fields E1, E3 only; S4 = S6 = E2 = 0, eqs 97-101)
// by A = P⁻¹Q (eq. 109). Its cE block (eq. 110) equals the 3-D cE of the full
// 6×6 inversion (eq. 8), and so do e and εS: for the 4mm class the dropped set
// {S4, E2} (coupled by d24 = d15) and {S6} are decoupled from the kept one in
// sE, d and εT, so the partial inversion acts block by block. The seed's remark
// after eq. 110 ("the cij of the 2D formulation differ from the 3D ones") does
// not hold for this reduction; it would for a plane-stress or plane-strain
// reduction (see model/README.md). Tolerance 1e-12: two 6×6 solves, condition ~10.
TEST(Material, AxisymmetricReducedEFormEqualsThe3dOne) {
  for (const auto& p : material_presets()) {
    const auto& d = p.material;
    Eigen::Matrix<double, 6, 6> pm, qm;  // eq. 107: P·[T1 T2 T3 T5 D1 D3] = Q·[S1 S2 S3 S5 E1 E3]
    pm << d.s_e11, d.s_e12, d.s_e13, 0, 0, 0,  //
        d.s_e12, d.s_e11, d.s_e13, 0, 0, 0,    //
        d.s_e13, d.s_e13, d.s_e33, 0, 0, 0,    //
        0, 0, 0, d.s_e44, 0, 0,                //
        0, 0, 0, -d.d15, 1, 0,                 //
        -d.d31, -d.d31, -d.d33, 0, 0, 1;
    qm << 1, 0, 0, 0, 0, -d.d31,  //
        0, 1, 0, 0, 0, -d.d31,    //
        0, 0, 1, 0, 0, -d.d33,    //
        0, 0, 0, 1, -d.d15, 0,    //
        0, 0, 0, 0, d.eps_t11, 0, //
        0, 0, 0, 0, 0, d.eps_t33;
    const Eigen::Matrix<double, 6, 6> a = pm.partialPivLu().solve(qm);  // eq. 109
    const auto e = to_e_form(d);
    // T = cE S − eᵀE, D = e S + εS E (eqs 1-2) in the order (1, 2, 3, 5 | 1, 3).
    EXPECT_LT(rel(a(0, 0), e.c_e11), 1e-12) << p.name;
    EXPECT_LT(rel(a(1, 1), e.c_e11), 1e-12) << p.name;
    EXPECT_LT(rel(a(0, 1), e.c_e12), 1e-12) << p.name;
    EXPECT_LT(rel(a(0, 2), e.c_e13), 1e-12) << p.name;
    EXPECT_LT(rel(a(2, 2), e.c_e33), 1e-12) << p.name;
    EXPECT_LT(rel(a(3, 3), e.c_e44), 1e-12) << p.name;
    EXPECT_LT(rel(a(5, 0), e.e31), 1e-12) << p.name;
    EXPECT_LT(rel(-a(0, 5), e.e31), 1e-12) << p.name;
    EXPECT_LT(rel(a(5, 2), e.e33), 1e-12) << p.name;
    EXPECT_LT(rel(a(5, 5), e.eps_s33), 1e-12) << p.name;
    if (d.d15 != 0) {
      EXPECT_LT(rel(a(4, 3), e.e15), 1e-12) << p.name;
      EXPECT_LT(rel(a(4, 4), e.eps_s11), 1e-12) << p.name;
    }
    // No coupling between the shear and the normal block (the 0s of eq. 110).
    EXPECT_LT(std::abs(a(0, 3)) + std::abs(a(2, 3)), 1e-12 * e.c_e11) << p.name;
  }
}
