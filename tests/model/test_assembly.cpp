// Mesh, DOF map and assembly: the split matrices (seed eqs 234-246) rebuild an
// independently assembled system (full material matrices, triplets) to 1e-12,
// total mass, symmetry, and the εS11 = 0 (isotropic class) non-singularity.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/SparseCholesky>
#include <cmath>

#include "model/element.hpp"
#include "model/material_presets.hpp"
#include "model/tube_model.hpp"

using namespace piezo::model;

namespace {

// Reference assembly written without the split: full cE (4×4), e (2×4), εS (2×2)
// in the FE ordering (S_zz, S_θθ, S_rr, γ_rz) / (E_z, E_r), structured rectangles.
AssembledMatrices reference_assembly(const TubeModel& tm, const PiezoMaterialE& m) {
  Eigen::Matrix4d c;
  c << m.c_e11, m.c_e12, m.c_e13, 0, m.c_e12, m.c_e11, m.c_e13, 0, m.c_e13, m.c_e13, m.c_e33, 0,
      0, 0, 0, m.c_e44;
  Eigen::Matrix<double, 2, 4> e;
  e << 0, 0, 0, m.e15, m.e31, m.e31, m.e33, 0;
  Eigen::Matrix2d eps;
  eps << m.eps_s11, 0, 0, m.eps_s33;
  const auto& mesh = tm.mesh();
  const auto& dofs = tm.dofs();
  const int nu = dofs.n_u();
  std::vector<Eigen::Triplet<double>> tm_, tk, tc, tp;
  const auto g = gauss_legendre(3);
  for (int el = 0; el < mesh.num_elements(); ++el) {
    const auto& en = mesh.element(el);
    const Node lo = mesh.nodes()[en[0]], hi = mesh.nodes()[en[8]];
    const double hr = hi.r - lo.r, hz = hi.z - lo.z;
    for (int qz = 0; qz < 3; ++qz)
      for (int qr = 0; qr < 3; ++qr) {
        const auto lx = lagrange2(g.x[qr]), ly = lagrange2(g.x[qz]);
        const auto dx = lagrange2_deriv(g.x[qr]), dy = lagrange2_deriv(g.x[qz]);
        const double r = lo.r + 0.5 * (1 + g.x[qr]) * hr;
        const double dv = 2 * M_PI * r * 0.25 * hr * hz * g.w[qr] * g.w[qz];
        Eigen::Matrix<double, 4, 18> bu = Eigen::Matrix<double, 4, 18>::Zero();
        Eigen::Matrix<double, 2, 9> bp;
        Eigen::Matrix<double, 1, 9> n;
        for (int b = 0; b < 3; ++b)
          for (int a = 0; a < 3; ++a) {
            const int k = 3 * b + a;
            n[k] = lx[a] * ly[b];
            const double nr = dx[a] * ly[b] * 2 / hr, nz = lx[a] * dy[b] * 2 / hz;
            bu(0, 2 * k + 1) = nz;
            bu(1, 2 * k) = n[k] / r;
            bu(2, 2 * k) = nr;
            bu(3, 2 * k) = nz;
            bu(3, 2 * k + 1) = nr;
            bp(0, k) = nz;
            bp(1, k) = nr;
          }
        const Eigen::Matrix<double, 18, 18> kuu = dv * bu.transpose() * c * bu;
        const Eigen::Matrix<double, 18, 9> kup = dv * bu.transpose() * e.transpose() * bp;
        const Eigen::Matrix<double, 9, 9> kpp = -dv * bp.transpose() * eps * bp;
        const Eigen::Matrix<double, 9, 9> mm = dv * tm.geometry().density_kg_m3 * n.transpose() * n;
        for (int a = 0; a < 9; ++a)
          for (int b = 0; b < 9; ++b) {
            for (int i = 0; i < 2; ++i) {
              tm_.emplace_back(2 * en[a] + i, 2 * en[b] + i, mm(a, b));
              for (int j = 0; j < 2; ++j)
                tk.emplace_back(2 * en[a] + i, 2 * en[b] + j, kuu(2 * a + i, 2 * b + j));
              if (dofs.phi(en[b]) >= 0)
                tc.emplace_back(2 * en[a] + i, dofs.phi(en[b]) - nu, kup(2 * a + i, b));
            }
            if (dofs.phi(en[a]) >= 0 && dofs.phi(en[b]) >= 0)
              tp.emplace_back(dofs.phi(en[a]) - nu, dofs.phi(en[b]) - nu, kpp(a, b));
          }
      }
  }
  AssembledMatrices r;
  r.m.resize(nu, nu);
  r.k_uu.resize(nu, nu);
  r.k_uphi.resize(nu, dofs.n_phi());
  r.k_phiphi.resize(dofs.n_phi(), dofs.n_phi());
  r.m.setFromTriplets(tm_.begin(), tm_.end());
  r.k_uu.setFromTriplets(tk.begin(), tk.end());
  r.k_uphi.setFromTriplets(tc.begin(), tc.end());
  r.k_phiphi.setFromTriplets(tp.begin(), tp.end());
  return r;
}

double rel_diff(const SpMat& a, const SpMat& b) { return (a - b).norm() / b.norm(); }

}  // namespace

TEST(Mesh, CountsAndDofMap) {
  TubeGeometry g;
  TubeMesh mesh(g, {2, 5});
  EXPECT_EQ(mesh.num_nodes(), 5 * 11);
  EXPECT_EQ(mesh.num_elements(), 10);
  DofMap dofs(mesh);
  EXPECT_EQ(dofs.n_u(), 110);
  EXPECT_EQ(dofs.n_phi(), 3 * 11 + 1);  // interior columns + one electrode DOF
  for (int n = 0; n < mesh.num_nodes(); ++n) {
    if (mesh.on_inner_surface(n)) {
      EXPECT_EQ(dofs.phi(n), -1);
    }
    if (mesh.on_outer_surface(n)) {
      EXPECT_EQ(dofs.phi(n), dofs.electrode());
    }
    EXPECT_EQ(mesh.mirror(mesh.mirror(n)), n);
    EXPECT_NEAR(mesh.nodes()[mesh.mirror(n)].z, -mesh.nodes()[n].z, 1e-15);
  }
  EXPECT_DOUBLE_EQ(mesh.nodes().front().r, g.inner_radius());
  EXPECT_DOUBLE_EQ(mesh.nodes().back().r, g.outer_radius());
  EXPECT_THROW(TubeMesh(g, {0, 4}), std::invalid_argument);
  EXPECT_EQ(MeshOptions({2, 24}).refined(1).n_axial, 48);
}

TEST(Assembly, SplitMatricesRebuildTheAssembledSystem) {
  // Acceptance: Σ c_ij K_cij etc. equals a direct assembly to 1e-12 relative
  // (only summation order differs → round-off ~1e-15).
  TubeModel tm(TubeGeometry{}, {2, 8});
  for (const char* name : {"apc850", "pzt5h"}) {
    const auto mat = to_e_form(find_preset(name).material);
    const auto a = tm.assemble(mat);
    const auto r = reference_assembly(tm, mat);
    EXPECT_LT(rel_diff(a.m, r.m), 1e-12) << name;
    EXPECT_LT(rel_diff(a.k_uu, r.k_uu), 1e-12) << name;
    EXPECT_LT(rel_diff(a.k_uphi, r.k_uphi), 1e-12) << name;
    EXPECT_LT(rel_diff(a.k_phiphi, r.k_phiphi), 1e-12) << name;
  }
  // The isotropic class, whose εS11 = 0 and e15 = 0 switch split terms off.
  const auto iso = to_e_form(to_d_form(IsotropicPiezoParams{6.66e10, 0.3333, -210e-12, 2294 * kEps0}));
  const auto a = tm.assemble(iso);
  const auto r = reference_assembly(tm, iso);
  EXPECT_LT(rel_diff(a.k_uu, r.k_uu), 1e-12);
  EXPECT_LT(rel_diff(a.k_uphi, r.k_uphi), 1e-12);
  EXPECT_LT(rel_diff(a.k_phiphi, r.k_phiphi), 1e-12);
}

TEST(Assembly, TotalMassSymmetryAndRigidMode) {
  TubeGeometry g;
  TubeModel tm(g, {2, 6});
  const SpMat& m = tm.split().m;
  Eigen::VectorXd uz = Eigen::VectorXd::Zero(tm.n_u());
  for (int n = 0; n < tm.mesh().num_nodes(); ++n) uz[tm.dofs().u_z(n)] = 1;
  const double mass = g.density_kg_m3 * M_PI * (std::pow(g.outer_radius(), 2) - std::pow(g.inner_radius(), 2)) * g.length_m;
  EXPECT_NEAR(uz.dot(m * uz) / mass, 1.0, 1e-13);
  for (const auto& k : tm.split().k_c) {
    EXPECT_LT(SpMat(k - SpMat(k.transpose())).norm(), 1e-14 * k.norm());
    EXPECT_LT((k * uz).norm(), 1e-6 * k.norm());  // rigid translation: no strain
  }
}

TEST(Assembly, IsotropicClassKphiphiIsNegativeDefinite) {
  // εS11 = 0 leaves only ∂φ/∂r in K_ΦΦ. With the inner surface grounded every free
  // potential is tied to ground along its radial line, and for the tensor-product
  // Q2 element K_εS33 = (radial stiffness) ⊗ (axial mass) — a Kronecker product of
  // positive definite matrices — so −K_ΦΦ stays positive definite (model/README.md).
  TubeModel tm(TubeGeometry{}, {2, 8});
  const auto iso = to_e_form(to_d_form(IsotropicPiezoParams{6.66e10, 0.3333, -210e-12, 2294 * kEps0}));
  ASSERT_EQ(iso.eps_s11, 0.0);
  const SpMat neg = -tm.assemble(iso).k_phiphi;
  Eigen::SimplicialLLT<SpMat> llt(neg);
  ASSERT_EQ(llt.info(), Eigen::Success);
  const Eigen::MatrixXd dense(neg);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(dense);
  EXPECT_GT(es.eigenvalues().minCoeff(), 1e-8 * es.eigenvalues().maxCoeff());
}
