// model/skyline_ldlt: the envelope LDLᵀ of the coupled system against a dense
// LU of the same constrained matrix, its envelope against the sparse minimum-
// degree factor's fill, and its report of a zero pivot; CoupledFactor's kept
// factor (model/coupled_solver.hpp) against a fresh one.
#include "model/skyline_ldlt.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <random>
#include <vector>

#include "model/coupled_solver.hpp"
#include "model/material.hpp"
#include "model/material_presets.hpp"
#include "model/tube_model.hpp"

namespace {
using namespace piezo::model;

PiezoMaterialE material() {
  return to_e_form(to_d_form(IsotropicPiezoParams{6.66e10, 0.3333, -210e-12, 2294 * kEps0}));
}

// The constrained matrix as CoupledFactor makes it: identity rows and columns.
Eigen::MatrixXd constrained_dense(const SpMat& a, const std::vector<int>& fixed) {
  Eigen::MatrixXd d(a);
  for (int f : fixed) {
    d.row(f).setZero();
    d.col(f).setZero();
    d(f, f) = 1.0;
  }
  return d;
}

TEST(SkylineLdlt, SolvesTheCoupledSystemAsADenseLuDoes) {
  TubeModel whole(TubeGeometry{}, MeshOptions{});
  const auto half = whole.upper_half();
  ASSERT_TRUE(half);
  for (const TubeModel* tm : {half.get(), &whole}) {
    SpMat a;
    const double sigma = -std::pow(2 * M_PI * 1000.0, 2);
    tm->system().combine(weights(material()), sigma, a);
    SkylineLdlt s;
    s.analyse(a);
    // The envelope is about the minimum-degree factor's fill (within 10 %:
    // 7059 against 6665 entries on the half tube).
    Eigen::SimplicialLDLT<SpMat, Eigen::Lower, Eigen::AMDOrdering<int>> amd(a);
    ASSERT_EQ(amd.info(), Eigen::Success);
    EXPECT_LT(double(s.envelope_size()), 1.1 * double(amd.matrixL().nestedExpression().nonZeros()));
    std::vector<int> plane = tm->symmetry_plane_dofs();
    const int electrode = tm->dofs().electrode();
    for (const bool grounded : {true, false}) {
      ASSERT_TRUE(s.factorize(a.valuePtr(), plane, grounded ? electrode : -1));
      std::vector<int> fixed = plane;
      if (grounded) fixed.push_back(electrode);
      const Eigen::MatrixXd dense = constrained_dense(a, fixed);
      std::mt19937 rng(3);
      std::normal_distribution<double> g;
      Eigen::VectorXd b(a.rows());
      for (Eigen::Index i = 0; i < b.size(); ++i) b[i] = g(rng);
      Eigen::VectorXd x(a.rows());
      s.solve(b.data(), x.data());
      const Eigen::VectorXd ref = dense.partialPivLu().solve(b);
      // Both backward stable; κ(A) of the scaled coupled system ~1e9 here.
      EXPECT_LT((x - ref).norm(), 1e-6 * ref.norm());
      EXPECT_LT((dense * x - b).norm(), 1e-10 * (dense.norm() * x.norm()));
    }
  }
}

TEST(SkylineLdlt, ReportsAZeroPivot) {
  // [[0, 1], [1, 0]]: indefinite, not strongly factorisable without pivoting.
  SpMat a(2, 2);
  a.insert(0, 0) = 0.0;
  a.insert(1, 0) = 1.0;
  a.insert(0, 1) = 1.0;
  a.insert(1, 1) = 0.0;
  a.makeCompressed();
  SkylineLdlt s;
  s.analyse(a);
  EXPECT_FALSE(s.factorize(a.valuePtr(), {}));
  // [[0, 1], [1, 2]] with DOF 0 constrained: its row and column zero, its
  // pivot one; DOF 1's pivot 2.
  a.coeffRef(1, 1) = 2.0;
  ASSERT_TRUE(s.factorize(a.valuePtr(), std::vector<int>{0}));
  const double b[2] = {0.0, 2.0};
  double x[2];
  s.solve(b, x);
  EXPECT_DOUBLE_EQ(x[0], 0.0);
  EXPECT_DOUBLE_EQ(x[1], 1.0);
}

}  // namespace

// CoupledFactor keeps its factor for a repeat of the same matrix and
// conditions (a port model's static solve, then its Lanczos at σ = 0): after
// any sequence of factorisations, a solve must be bit-equal to a fresh
// factor's of the same matrix and conditions — a changed material, shift,
// end mass, electrode or set of clamped DOFs is factorised again.
TEST(CoupledFactor, KeepsItsFactorOnlyForTheSameMatrixAndConditions) {
  TubeModel whole(TubeGeometry{}, MeshOptions{});
  const auto half = whole.upper_half();
  ASSERT_TRUE(half);
  const std::vector<int>& plane = half->symmetry_plane_dofs();
  const std::vector<int> more = {plane.front(), 0, 1};
  PiezoMaterialE other = material();
  other.c_e11 *= 1.0 + 1e-6;
  struct Step {
    const PiezoMaterialE* m;
    double sigma;
    Electrodes electrodes;
    const std::vector<int>* clamped;
    double mass;
  };
  const PiezoMaterialE base = material();
  const double shift = -std::pow(2 * M_PI * 1000.0, 2);
  const std::vector<Step> steps = {
      {&base, 0.0, Electrodes::short_circuit, &plane, 0.0},
      {&base, 0.0, Electrodes::short_circuit, &plane, 0.02},  // σ = 0: the mass does not enter (kept)
      {&base, 0.0, Electrodes::short_circuit, &plane, 0.0},   // the same again (kept)
      {&base, 0.0, Electrodes::open_circuit, &plane, 0.0},    // another electrode condition
      {&base, 0.0, Electrodes::short_circuit, &more, 0.0},    // other clamped DOFs
      {&base, 0.0, Electrodes::short_circuit, &plane, 0.0},
      {&other, 0.0, Electrodes::short_circuit, &plane, 0.0},  // another material, 1e-6 away
      {&other, shift, Electrodes::short_circuit, &plane, 0.02},
      {&other, shift, Electrodes::short_circuit, &plane, 0.0},  // another end mass at σ ≠ 0
      {&base, 0.0, Electrodes::short_circuit, &plane, 0.0},
  };
  CoupledFactor kept(*half);
  std::mt19937 rng(5);
  std::normal_distribution<double> g;
  Eigen::VectorXd b(half->dofs().n_total());
  for (Eigen::Index i = 0; i < b.size(); ++i) b[i] = g(rng);
  for (std::size_t k = 0; k < steps.size(); ++k) {
    const Step& st = steps[k];
    const auto w = weights(*st.m);
    ASSERT_TRUE(kept.factorize(w, st.sigma, st.electrodes, *st.clamped, st.mass)) << "step " << k;
    CoupledFactor fresh(*half);
    ASSERT_TRUE(fresh.factorize(w, st.sigma, st.electrodes, *st.clamped, st.mass)) << "step " << k;
    Eigen::VectorXd rhs = b, xk, xf;
    for (int d : *st.clamped) rhs[d] = 0.0;
    kept.solve(rhs, xk);
    fresh.solve(rhs, xf);
    ASSERT_EQ(xk.size(), xf.size());
    for (Eigen::Index i = 0; i < xk.size(); ++i) ASSERT_EQ(xk[i], xf[i]) << "step " << k << ", entry " << i;
  }
}
