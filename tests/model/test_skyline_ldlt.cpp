// model/skyline_ldlt: the envelope LDLᵀ of the coupled system against a dense
// LU of the same constrained matrix, its envelope against the sparse minimum-
// degree factor's fill, and its report of a zero pivot.
#include "model/skyline_ldlt.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <random>
#include <vector>

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
