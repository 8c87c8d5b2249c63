// update/mode_shape_cmcm: the direct CMCM with target mode shapes of seed
// Appendix D, on our FE tube: Table D.1's numerical study (original and target
// from the same FE model), exact and with noisy shapes.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "model/material_presets.hpp"
#include "tests/support/tube_fixture.hpp"
#include "update/condensed_stiffness.hpp"
#include "update/appendix_d_study.hpp"
#include "update/mode_shape_cmcm.hpp"

namespace piezo::update {
namespace {

using model::Electrodes;
using model::kEps0;

// Table D.1: table_d1_original() / table_d1_target() (update/appendix_d_study.hpp,
// the seed's absolute e-form numbers; εS11 = 0 as D.2 assumes).

// The exact α of the target against the base, in the unknowns' order.
std::array<double, kModeShapeUnknowns> exact_alpha(const model::PiezoMaterialE& b,
                                                   const model::PiezoMaterialE& t) {
  const auto wb = model::weights(b), wt = model::weights(t);
  std::array<double, kModeShapeUnknowns> a{};
  for (int n = 0; n < 5; ++n) a[n] = wt[n] / wb[n] - 1.0;
  const int k[6] = {0, 1, 2, 0, 0, 1}, l[6] = {0, 1, 2, 1, 2, 2};
  for (int u = 0; u < 6; ++u)
    a[5 + u] =
        (wt[5 + k[u]] * wt[5 + l[u]] / t.eps_s33) / (wb[5 + k[u]] * wb[5 + l[u]] / b.eps_s33) - 1.0;
  return a;
}

class ModeShapeCmcm : public test::TubeFixture {
 protected:
  static void SetUpTestSuite() {
    TubeFixture::SetUpTestSuite();
    target_ = table_d1_target();
    const ModeShapeCmcmOptions o;
    targets_.short_circuit =
        elastic_modes(solver_->solve(target_, Electrodes::short_circuit, o.modal), 12);
    targets_.open_circuit =
        elastic_modes(solver_->solve(target_, Electrodes::open_circuit, o.modal), 12);
    targets_.eps_t33 =
        model::to_d_form(target_).eps_t33;  // exact; the capacitance's value is in README
  }
  static double rel(double a, double b) { return a / b - 1.0; }
  static void print(const char* what, const ModeShapeCmcmResult& r) {
    const auto t = table_d1_target();
    const double tv[9] = {t.c_e11,   t.c_e12, t.c_e13, t.c_e33, t.c_e44,
                          t.eps_s33, t.e33,   t.e31,   t.e15};
    const auto& u = r.updated;
    const double uv[9] = {r.c_e[0],  r.c_e[1], r.c_e[2], r.c_e[3], r.c_e[4],
                          u.eps_s33, u.e33,    u.e31,    u.e15};
    const char* names[9] = {"cE11", "cE12", "cE13", "cE33", "cE44", "epsS33", "e33", "e31", "e15"};
    std::printf("[%s] %s: rank1 defect %.2e, residual lifted %.2e refined %.2e, GN %d\n", what,
                to_string(r.staging), r.rank1_defect, r.residual_lifted, r.residual,
                r.refine_iterations);
    for (int p = 0; p < 9; ++p)
      std::printf("  %-7s target %.6g updated %.6g  rel %+.3e\n", names[p], tv[p], uv[p],
                  rel(uv[p], tv[p]));
    for (const auto& eq : r.systems) {
      std::printf(
          "  system %lldx%lld rank %d, singular values:", static_cast<long long>(eq.g.rows()),
          static_cast<long long>(eq.g.cols()), eq.rank);
      for (Eigen::Index s = 0; s < eq.singular_values.size(); ++s)
        std::printf(" %.2e", eq.singular_values[s]);
      std::printf("\n  independence:");
      for (std::size_t c = 0; c < eq.unknowns.size(); ++c)
        std::printf(" %s %.2e", mode_shape_unknown_name(eq.unknowns[c]),
                    eq.independence[static_cast<Eigen::Index>(c)]);
      std::printf("\n");
      for (Eigen::Index c = eq.g.cols() - 3; c < eq.g.cols(); ++c) {
        std::printf("  weak direction sigma %.2e:", eq.singular_values[c]);
        for (std::size_t u = 0; u < eq.unknowns.size(); ++u)
          std::printf(" %s %+.2f", mode_shape_unknown_name(eq.unknowns[u]),
                      eq.right_singular_vectors(static_cast<Eigen::Index>(u), c));
        std::printf("\n");
      }
    }
  }
  static inline model::PiezoMaterialE target_;
  static inline ModeShapeTargets targets_;
};

void expect_material_near(const ModeShapeCmcmResult& r, const model::PiezoMaterialE& t,
                          double tol) {
  EXPECT_NEAR(r.updated.c_e11 / t.c_e11, 1.0, tol);
  EXPECT_NEAR(r.updated.c_e12 / t.c_e12, 1.0, tol);
  EXPECT_NEAR(r.updated.c_e13 / t.c_e13, 1.0, tol);
  EXPECT_NEAR(r.updated.c_e33 / t.c_e33, 1.0, tol);
  EXPECT_NEAR(r.updated.c_e44 / t.c_e44, 1.0, tol);
  EXPECT_NEAR(r.updated.eps_s33 / t.eps_s33, 1.0, tol);
  EXPECT_NEAR(r.updated.e31 / t.e31, 1.0, tol);
  EXPECT_NEAR(r.updated.e33 / t.e33, 1.0, tol);
  EXPECT_NEAR(r.updated.e15 / t.e15, 1.0, tol);
}

// Exact target shapes: with the coupling terms lifted, K is exactly linear in
// the eleven unknowns, so eq. 187 holds exactly at the true α and G has full
// rank (11) — the answer is exact up to the modal solver's accuracy
// (Lanczos tolerance 1e-10) times ‖G⁺‖ = 1/σ_min ≈ 13: 1e-8 with margin
// (measured 2.4e-10). D.11 with the exact εT33 then gives e31, e33, εS33.
TEST_F(ModeShapeCmcm, ExactShapesRecoverTableD1) {
  const auto base = table_d1_original();
  const auto r = mode_shape_cmcm(*tube_, *solver_, base, targets_);
  print("exact shapes", r);
  ASSERT_TRUE(r.ok) << r.message;
  ASSERT_EQ(r.systems.size(), 1u);
  EXPECT_EQ(r.systems[0].rank, kModeShapeUnknowns);
  const auto a = exact_alpha(base, target_);
  for (int u = 0; u < kModeShapeUnknowns; ++u) {
    EXPECT_NEAR(r.alpha_lifted[u], a[u], 1e-8) << mode_shape_unknown_name(u);
    EXPECT_NEAR(r.alpha[u], a[u], 1e-8) << mode_shape_unknown_name(u);
  }
  EXPECT_LT(r.rank1_defect, 1e-8);
  expect_material_near(r, target_, 1e-8);
}

// The diagonal pairs alone (2 × 12 rows) still determine all eleven unknowns
// from exact shapes, on a much worse conditioned system (σ_min/σ_max ≈ 2e-6,
// ‖G⁺‖ ≈ 8e4): the same bound gives 1e-10 × 8e4 ≈ 1e-5 (measured 4e-10).
TEST_F(ModeShapeCmcm, ExactShapesDiagonalPairsOnly) {
  ModeShapeCmcmOptions o;
  o.cross_modes = false;
  const auto r = mode_shape_cmcm(*tube_, *solver_, table_d1_original(), targets_, o);
  print("exact shapes, i = j only", r);
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_EQ(r.systems[0].g.rows(), 24);
  EXPECT_EQ(r.systems[0].rank, kModeShapeUnknowns);
  expect_material_near(r, target_, 1e-5);
}

// The seed's staging: D.1 holds the coupling at the base model's. On our FE
// model the potentials inside the wall are condensed in the short circuit as
// well, so the short-circuit stiffness carries the coupling terms and D.1
// absorbs their change into the elastic constants (cE13, cE33 +59 %). With the
// base's coupling already equal to the target's, the same staging is exact —
// the bias is that term and nothing else.
TEST_F(ModeShapeCmcm, SeedStagingIsBiasedByTheShortCircuitCoupling) {
  ModeShapeCmcmOptions o;
  o.staging = ModeShapeStaging::seed;
  const auto r = mode_shape_cmcm(*tube_, *solver_, table_d1_original(), targets_, o);
  print("exact shapes", r);
  ASSERT_EQ(r.systems.size(), 2u);
  EXPECT_GT(std::abs(rel(r.c_e[2], target_.c_e13)), 0.05);
  EXPECT_GT(std::abs(rel(r.c_e[3], target_.c_e33)), 0.05);

  auto base = table_d1_original();
  base.e31 = target_.e31;
  base.e33 = target_.e33;
  base.e15 = target_.e15;
  base.eps_s33 = target_.eps_s33;
  const auto rk = mode_shape_cmcm(*tube_, *solver_, base, targets_, o);
  print("exact shapes, coupling known", rk);
  ASSERT_TRUE(rk.ok) << rk.message;
  expect_material_near(rk, target_, 1e-8);
}

// The seed's reading of D.10 as eq. 173 (√ cross terms linearised): on exact
// shapes its answer is biased by the linearisation, not by the data. For
// Table D.1 the e31e15 term's factor is √(2.338 · 0.9235) = 1.469 against the
// linearised 1 + (1.338 − 0.0765)/2 = 1.631 (+11 %), so the eight unknowns
// cannot fit the exact equations: a residual and percent-level errors
// (measured 1.1-9.0 %) where the lifted form is exact.
TEST_F(ModeShapeCmcm, SeedLinearisationOfTheCrossTermsIsBiased) {
  ModeShapeCmcmOptions o;
  o.linearise_cross_terms = true;
  const auto r = mode_shape_cmcm(*tube_, *solver_, table_d1_original(), targets_, o);
  print("exact shapes, D.10 linearised", r);
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_EQ(r.systems[0].g.cols(), 8);
  EXPECT_GT(r.residual, 1e3 * ModeShapeCmcmResult{}.residual + 1e-3);
  const double worst = std::max({std::abs(rel(r.updated.c_e44, target_.c_e44)),
                                 std::abs(rel(r.updated.e15, target_.e15)),
                                 std::abs(rel(r.updated.e31, target_.e31))});
  EXPECT_GT(worst, 1e-2);
}

// Table D.1's ratios applied to our APC850 preset (e-form, εS11 set to 0 as
// D.2 assumes): the same exactness on another material, bound as above.
TEST_F(ModeShapeCmcm, ExactShapesTableD1RatiosOnApc850) {
  auto base = model::to_e_form(model::find_preset("apc850").material);
  base.eps_s11 = 0;
  auto t = base;
  t.c_e11 *= 1.2;
  t.c_e12 *= 1.16;
  t.c_e13 *= 1.1;
  t.c_e33 *= 1.06;
  t.c_e44 *= 1.15;
  t.eps_s33 *= 800.0 / 538.0;
  t.e33 *= 30.0 / 17.3;
  t.e31 *= 10.0 / 5.363;
  t.e15 *= 15.0 / 12.8;
  const ModeShapeCmcmOptions o;
  ModeShapeTargets tg;
  tg.short_circuit = elastic_modes(solver_->solve(t, Electrodes::short_circuit, o.modal), 12);
  tg.open_circuit = elastic_modes(solver_->solve(t, Electrodes::open_circuit, o.modal), 12);
  tg.eps_t33 = model::to_d_form(t).eps_t33;
  const auto r = mode_shape_cmcm(*tube_, *solver_, base, tg);
  ASSERT_TRUE(r.ok) << r.message;
  std::printf("APC850 x Table D.1 ratios: rank %d, sigma_min/max %.2e, rank1 defect %.2e\n",
              r.systems[0].rank,
              r.systems[0].singular_values.tail(1)[0] / r.systems[0].singular_values[0],
              r.rank1_defect);
  EXPECT_EQ(r.systems[0].rank, kModeShapeUnknowns);
  expect_material_near(r, t, 1e-8);
}

TEST_F(ModeShapeCmcm, RejectsWhatAppendixDDoesNotCover) {
  auto base = table_d1_original();
  base.eps_s11 = 1e-9;
  EXPECT_THROW(mode_shape_cmcm(*tube_, *solver_, base, targets_), std::invalid_argument);
  base = table_d1_original();
  base.e15 = 0;
  EXPECT_THROW(mode_shape_cmcm(*tube_, *solver_, base, targets_), std::invalid_argument);
  ModeShapeTargets t = targets_;
  t.eps_t33 = 0;
  EXPECT_THROW(mode_shape_cmcm(*tube_, *solver_, table_d1_original(), t), std::invalid_argument);
}

// Two noise models for the target shapes, each independent between modes and
// electrode conditions:
//  white:  δ_j ~ N(0, (nu·rms(Φ*_j))² I), every DOF on its own (a measurement
//          at every node);
//  modal:  δ_j = nu·Σ_k ξ_k φ*_k over the other target modes k of the lowest
//          `kContamination` (M-normalised, ξ ~ N(0, 1)): leakage between modes,
//          what a modal identification leaves in a shape — smooth.
enum class Noise { white, modal };
constexpr int kContamination = 24;

// First-order covariance of the lifted α. Row m = (i, j) of eq. 187 is
// h_m = Φ_iᵀ(K* − λ*_jM)Φ*_j / Φ_iᵀKΦ*_j, zero at the truth, so
// δh_m = w_mᵀδ_j / K0_m with w_m = (K* − λ*_jM)Φ_i, and δα = −G⁺δh.
// For modal noise w_mᵀφ*_k = (λ*_k − λ*_j)Φ_iᵀMφ*_k.
class ErrorModel {
 public:
  ErrorModel(const model::TubeModel& tube, model::ModalSolver& solver,
             const model::PiezoMaterialE& base, const model::PiezoMaterialE& target,
             const ModeShapeTargets& t)
      : n_u_(tube.n_u()) {
    const ModeShapeCmcmOptions o;
    model::ModalOptions wide = o.modal;
    wide.n_modes = kContamination + 1;
    const Eigen::MatrixXd eye = Eigen::MatrixXd::Identity(n_u_, n_u_);
    for (int e = 0; e < 2; ++e) {
      const Electrodes el = e == 0 ? Electrodes::short_circuit : Electrodes::open_circuit;
      Side& s = side_[e];
      const ModalData md = elastic_modes(solver.solve(base, el, o.modal), o.n_model_modes);
      const ModalData& td = e == 0 ? t.short_circuit : t.open_circuit;
      s.basis = elastic_modes(solver.solve(target, el, wide), kContamination);
      s.phis = td.shapes;
      s.lambda_star = td.lambda;
      s.w_k = CondensedStiffness(tube, target, el).bilinear(md.shapes, eye);
      s.w_m = md.shapes.transpose() * (tube.split().m * eye);
      s.mb = md.shapes.transpose() * (tube.split().m * s.basis.shapes);
      s.k0 = CondensedStiffness(tube, base, el).bilinear(md.shapes, td.shapes);
    }
  }
  Eigen::MatrixXd covariance(const ModeShapeEquations& eq, Noise noise, double nu) const {
    const Eigen::Index rows = eq.g.rows();
    Eigen::MatrixXd sigma_h = Eigen::MatrixXd::Zero(rows, rows);
    for (Eigen::Index m = 0; m < rows; ++m)
      for (Eigen::Index q = 0; q < rows; ++q) {
        if (eq.electrodes[m] != eq.electrodes[q] || eq.pairs[m].second != eq.pairs[q].second)
          continue;
        const Side& s = side_[eq.electrodes[m] == Electrodes::short_circuit ? 0 : 1];
        const int j = eq.pairs[m].second, i1 = eq.pairs[m].first, i2 = eq.pairs[q].first;
        double c = 0;
        if (noise == Noise::white) {
          const double sj = nu * s.phis.col(j).norm() / std::sqrt(static_cast<double>(n_u_));
          const Eigen::VectorXd w1 = s.w_k.row(i1) - s.lambda_star[j] * s.w_m.row(i1);
          const Eigen::VectorXd w2 = s.w_k.row(i2) - s.lambda_star[j] * s.w_m.row(i2);
          c = sj * sj * w1.dot(w2);
        } else {
          for (int k = 0; k < kContamination; ++k) {
            if (k == j) continue;
            const double dl = s.basis.lambda[k] - s.lambda_star[j];
            c += nu * nu * dl * dl * s.mb(i1, k) * s.mb(i2, k);
          }
        }
        sigma_h(m, q) = c / (s.k0(i1, j) * s.k0(i2, j));
      }
    const Eigen::MatrixXd gp = eq.g.completeOrthogonalDecomposition().pseudoInverse();
    return gp * sigma_h * gp.transpose();
  }
  ModalData perturb(const ModalData& d, Electrodes el, Noise noise, double nu,
                    std::mt19937& rng) const {
    std::normal_distribution<double> n01;
    const Side& s = side_[el == Electrodes::short_circuit ? 0 : 1];
    ModalData o = d;
    for (Eigen::Index c = 0; c < o.shapes.cols(); ++c) {
      if (noise == Noise::white) {
        const double sd = nu * d.shapes.col(c).norm() / std::sqrt(static_cast<double>(n_u_));
        for (Eigen::Index r = 0; r < o.shapes.rows(); ++r) o.shapes(r, c) += sd * n01(rng);
      } else {
        for (int k = 0; k < kContamination; ++k)
          if (k != c) o.shapes.col(c) += nu * n01(rng) * s.basis.shapes.col(k);
      }
    }
    return o;
  }

 private:
  struct Side {
    ModalData basis;  // target modes for the modal noise
    Eigen::MatrixXd phis, w_k, w_m, mb, k0;
    Eigen::VectorXd lambda_star;
  };
  int n_u_;
  std::array<Side, 2> side_;
};

struct NoiseRun {
  double rms_z = 0;                   // lifted α errors in units of the predicted σ
  std::array<double, 5> sigma_c{};    // predicted σ of α1..α5 (= relative σ of cE_n)
  std::array<double, 5> max_err_c{};  // largest |relative error| of the refined cE_n over the seeds
  int physical = 0;                   // runs that ended with a physical material
};

NoiseRun run_noise(const ErrorModel& em, const ModeShapeTargets& exact_t,
                   const ModeShapeEquations& eq, const model::TubeModel& tube,
                   model::ModalSolver& solver, const model::PiezoMaterialE& base,
                   const model::PiezoMaterialE& target, Noise noise, double nu, unsigned seeds,
                   const ModeShapeCmcmOptions& opt = {}) {
  const Eigen::MatrixXd cov = em.covariance(eq, noise, nu);
  const auto a_true = exact_alpha(base, target);
  NoiseRun out;
  std::printf("%s noise %.1e, predicted sigma of alpha:", noise == Noise::white ? "white" : "modal",
              nu);
  for (int u = 0; u < kModeShapeUnknowns; ++u) std::printf(" %.2e", std::sqrt(cov(u, u)));
  std::printf("\n");
  for (int n = 0; n < 5; ++n) out.sigma_c[n] = std::sqrt(cov(n, n));
  const double tc[5] = {target.c_e11, target.c_e12, target.c_e13, target.c_e33, target.c_e44};
  double z2 = 0;
  int nz = 0;
  for (unsigned seed = 1; seed <= seeds; ++seed) {
    std::mt19937 rng(seed);
    ModeShapeTargets t = exact_t;
    t.short_circuit = em.perturb(exact_t.short_circuit, Electrodes::short_circuit, noise, nu, rng);
    t.open_circuit = em.perturb(exact_t.open_circuit, Electrodes::open_circuit, noise, nu, rng);
    const auto r = mode_shape_cmcm(tube, solver, base, t, opt);
    std::printf("  seed %u %s z:", seed, r.ok ? "ok          " : "non-physical");
    for (int u = 0; u < kModeShapeUnknowns; ++u) {
      const double z = (r.alpha_lifted[u] - a_true[u]) / std::sqrt(cov(u, u));
      std::printf(" %+.2f", z);
      z2 += z * z;
      ++nz;
    }
    std::printf(" | rel err cE");
    for (int n = 0; n < 5; ++n) {
      const double e = r.c_e[n] / tc[n] - 1.0;
      out.max_err_c[n] = std::max(out.max_err_c[n], std::abs(e));
      std::printf(" %+.1e", e);
    }
    if (r.ok) {
      ++out.physical;
      const auto& u = r.updated;
      std::printf(" epsS33 %+.1e e31 %+.1e e33 %+.1e e15 %+.1e", u.eps_s33 / target.eps_s33 - 1,
                  u.e31 / target.e31 - 1, u.e33 / target.e33 - 1, u.e15 / target.e15 - 1);
    }
    std::printf("\n");
  }
  out.rms_z = std::sqrt(z2 / nz);
  std::printf("  rms z %.3f over %d, physical %d/%u\n", out.rms_z, nz, out.physical, seeds);
  return out;
}

// Noisy shapes. (1) In the linear regime (nu = 1e-6) the lifted α's errors
// must follow the first-order prediction: the RMS of error/σ over 8 seeds ×
// 11 unknowns is 1 for a correct prediction; the unknowns' errors are strongly
// correlated within a seed (cE11..cE33 move together), ~3 independent per
// seed, so its spread is ≈ 0.14 and [0.6, 1.5] is asserted (measured 0.71-1.30).
// (2) At the 1 % the predicted σ of the elastic α's exceeds 0.5 for
// both noise models with the seed's N_i × N_j rows (and 0.5 for cE11 with
// i = j rows under modal noise): Appendix D cannot identify the constants
// from 1 %-accurate shapes on this tube; the observed errors must be of that
// scale (RMS of error/σ between 0.05 and 3: past the linear regime the
// answers saturate or leave the physical domain, so not 1).
TEST_F(ModeShapeCmcm, NoisyShapesFollowTheFirstOrderPrediction) {
  const auto base = table_d1_original();
  ModeShapeCmcmOptions diag;
  diag.cross_modes = false;
  const auto exact = mode_shape_cmcm(*tube_, *solver_, base, targets_);
  const auto exact_diag = mode_shape_cmcm(*tube_, *solver_, base, targets_, diag);
  ASSERT_TRUE(exact.ok && exact_diag.ok);
  const ErrorModel em(*tube_, *solver_, base, target_, targets_);
  for (Noise noise : {Noise::white, Noise::modal}) {
    for (bool cross : {true, false}) {
      const auto& eq = cross ? exact.systems[0] : exact_diag.systems[0];
      const ModeShapeCmcmOptions& o = cross ? ModeShapeCmcmOptions{} : diag;
      std::printf("%s rows: ", cross ? "all" : "i = j");
      const NoiseRun lin =
          run_noise(em, targets_, eq, *tube_, *solver_, base, target_, noise, 1e-6, 8, o);
      EXPECT_GT(lin.rms_z, 0.6);
      EXPECT_LT(lin.rms_z, 1.5);
      EXPECT_EQ(lin.physical, 8);
      std::printf("%s rows: ", cross ? "all" : "i = j");
      (void)run_noise(em, targets_, eq, *tube_, *solver_, base, target_, noise, 1e-3, 8, o);
      std::printf("%s rows: ", cross ? "all" : "i = j");
      const NoiseRun one =
          run_noise(em, targets_, eq, *tube_, *solver_, base, target_, noise, 1e-2, 8, o);
      EXPECT_GT(one.rms_z, 0.05);
      EXPECT_LT(one.rms_z, 3.0);
      if (cross)
        for (int n = 0; n < 5; ++n) EXPECT_GT(one.sigma_c[n], 0.5) << n;
      else
        EXPECT_GT(one.sigma_c[0], 0.5);
    }
  }
}

}  // namespace
}  // namespace piezo::update
