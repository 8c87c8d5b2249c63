#include "model/element.hpp"

#include <Eigen/LU>
#include <cmath>
#include <stdexcept>
#include <string>

namespace piezo::model {

GaussRule gauss_legendre(int n) {
  GaussRule g;
  g.n = n;
  switch (n) {
    case 1:
      g.x = {0, 0, 0, 0};
      g.w = {2, 0, 0, 0};
      break;
    case 2: {
      const double a = 1.0 / std::sqrt(3.0);
      g.x = {-a, a, 0, 0};
      g.w = {1, 1, 0, 0};
      break;
    }
    case 3: {
      const double a = std::sqrt(0.6);
      g.x = {-a, 0, a, 0};
      g.w = {5.0 / 9, 8.0 / 9, 5.0 / 9, 0};
      break;
    }
    case 4: {
      const double a = std::sqrt(3.0 / 7 - 2.0 / 7 * std::sqrt(1.2));
      const double b = std::sqrt(3.0 / 7 + 2.0 / 7 * std::sqrt(1.2));
      const double wa = (18 + std::sqrt(30.0)) / 36, wb = (18 - std::sqrt(30.0)) / 36;
      g.x = {-b, -a, a, b};
      g.w = {wb, wa, wa, wb};
      break;
    }
    default:
      throw std::invalid_argument("gauss_legendre: n must be 1..4, got " + std::to_string(n));
  }
  return g;
}

std::array<double, 3> lagrange2(double xi) {
  return {0.5 * xi * (xi - 1.0), 1.0 - xi * xi, 0.5 * xi * (xi + 1.0)};
}

std::array<double, 3> lagrange2_deriv(double xi) { return {xi - 0.5, -2.0 * xi, xi + 0.5}; }

Q2Point q2_point(const std::array<Node, kElemNodes>& x, double xi, double eta) {
  const auto lx = lagrange2(xi), ly = lagrange2(eta);
  const auto dlx = lagrange2_deriv(xi), dly = lagrange2_deriv(eta);
  std::array<double, 9> dn_dxi{}, dn_deta{};
  Q2Point q;
  for (int b = 0; b < 3; ++b)
    for (int a = 0; a < 3; ++a) {
      q.n[3 * b + a] = lx[a] * ly[b];
      dn_dxi[3 * b + a] = dlx[a] * ly[b];
      dn_deta[3 * b + a] = lx[a] * dly[b];
    }
  // Isoparametric map (r, z)(ξ, η).
  Eigen::Matrix2d jac = Eigen::Matrix2d::Zero();  // [[dr/dξ, dz/dξ], [dr/dη, dz/dη]]
  for (int a = 0; a < 9; ++a) {
    q.r += q.n[a] * x[a].r;
    jac(0, 0) += dn_dxi[a] * x[a].r;
    jac(0, 1) += dn_dxi[a] * x[a].z;
    jac(1, 0) += dn_deta[a] * x[a].r;
    jac(1, 1) += dn_deta[a] * x[a].z;
  }
  q.det = jac.determinant();
  if (!(q.det > 0) || !(q.r > 0)) return q;
  const Eigen::Matrix2d jinv = jac.inverse();
  for (int a = 0; a < 9; ++a) {
    q.dr[a] = jinv(0, 0) * dn_dxi[a] + jinv(0, 1) * dn_deta[a];
    q.dz[a] = jinv(1, 0) * dn_dxi[a] + jinv(1, 1) * dn_deta[a];
  }
  return q;
}

void element_split(const std::array<Node, kElemNodes>& x, int gauss_points, ElementSplit& out) {
  const GaussRule g = gauss_legendre(gauss_points);
  for (auto& k : out.k) k.setZero();
  out.m.setZero();

  // Unit material derivatives in the FE ordering (strains S1,S2,S3,S5; fields E1,E3).
  std::array<Eigen::Matrix4d, 5> dc;
  for (auto& m : dc) m.setZero();
  dc[0](0, 0) = dc[0](1, 1) = 1;                                     // cE11
  dc[1](0, 1) = dc[1](1, 0) = 1;                                     // cE12
  dc[2](0, 2) = dc[2](2, 0) = dc[2](1, 2) = dc[2](2, 1) = 1;          // cE13
  dc[3](2, 2) = 1;                                                   // cE33
  dc[4](3, 3) = 1;                                                   // cE44 (= cE55)
  std::array<Eigen::Matrix<double, 2, 4>, 3> de;
  for (auto& m : de) m.setZero();
  de[0](1, 0) = de[0](1, 1) = 1;  // e31: D3 ← S1, S2
  de[1](1, 2) = 1;                // e33: D3 ← S3
  de[2](0, 3) = 1;                // e15: D1 ← S5
  std::array<Eigen::Matrix2d, 2> deps;
  deps[0] << 1, 0, 0, 0;  // εS11 (E1 = E_z)
  deps[1] << 0, 0, 0, 1;  // εS33 (E3 = E_r)

  Eigen::Matrix<double, 4, 18> bu;
  Eigen::Matrix<double, 2, 9> bphi;
  Eigen::Matrix<double, 2, 18> nu;
  for (int qz = 0; qz < g.n; ++qz)
    for (int qr = 0; qr < g.n; ++qr) {
      const Q2Point q = q2_point(x, g.x[qr], g.x[qz]);
      const double r = q.r, det = q.det;
      if (!(det > 0) || !(r > 0))
        throw std::invalid_argument("element_split: degenerate or inverted element");
      const double dv = 2.0 * M_PI * r * det * g.w[qr] * g.w[qz];
      bu.setZero();
      nu.setZero();
      const auto& n = q.n;
      for (int a = 0; a < 9; ++a) {
        const double dr = q.dr[a], dz = q.dz[a];
        bu(0, 2 * a + 1) = dz;     // S_zz
        bu(1, 2 * a) = n[a] / r;   // S_θθ
        bu(2, 2 * a) = dr;         // S_rr
        bu(3, 2 * a) = dz;         // γ_rz
        bu(3, 2 * a + 1) = dr;
        bphi(0, a) = dz;           // −E_z
        bphi(1, a) = dr;           // −E_r
        nu(0, 2 * a) = n[a];
        nu(1, 2 * a + 1) = n[a];
      }
      for (int p = 0; p < 5; ++p) out.k[p].topLeftCorner<18, 18>() += dv * bu.transpose() * dc[p] * bu;
      for (int p = 0; p < 3; ++p) {
        const Eigen::Matrix<double, 18, 9> kup = dv * bu.transpose() * de[p].transpose() * bphi;
        out.k[5 + p].topRightCorner<18, 9>() += kup;
        out.k[5 + p].bottomLeftCorner<9, 18>() += kup.transpose();
      }
      for (int p = 0; p < 2; ++p)
        out.k[8 + p].bottomRightCorner<9, 9>() -= dv * bphi.transpose() * deps[p] * bphi;
      out.m.topLeftCorner<18, 18>() += dv * nu.transpose() * nu;
    }
}

}  // namespace piezo::model
