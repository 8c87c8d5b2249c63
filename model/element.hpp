#pragma once
// The 9-node axisymmetric piezoelectric element (seed §3.1.1 and §3.2.3) and its
// Gauss quadrature. Local DOFs: [u_r0, u_z0, …, u_r8, u_z8 | φ0 … φ8] (27).
// Kinematics (eqs 102-105), in IEEE material axes 1 = z, 2 = θ, 3 = r (poling):
//   S = [S_zz, S_θθ = u_r/r, S_rr, γ_rz]  = [S1, S2, S3, S5] = B_u u   (eq. 69)
//   E = [E_z, E_r] = [E1, E3] = −B_φ φ                                 (eq. 70)
// All integrals run over the full circumference: dV = 2π r dr dz.
#include <Eigen/Core>
#include <array>

#include "model/material.hpp"
#include "model/mesh.hpp"

namespace piezo::model {

inline constexpr int kElemNodes = 9;
inline constexpr int kElemDofs = 27;
using ElementMatrix = Eigen::Matrix<double, kElemDofs, kElemDofs>;

// Gauss–Legendre points and weights on [−1, 1], n = 1…4.
struct GaussRule {
  int n = 0;
  std::array<double, 4> x{}, w{};
};
GaussRule gauss_legendre(int n);

// 1-D quadratic Lagrange basis on nodes −1, 0, 1 and its derivative.
std::array<double, 3> lagrange2(double xi);
std::array<double, 3> lagrange2_deriv(double xi);

// The 9-node element at (ξ, η), mapped to (r, z): N_a, ∂N_a/∂r, ∂N_a/∂z, the
// radius and the Jacobian determinant (callers refuse det ≤ 0 or r ≤ 0).
struct Q2Point {
  std::array<double, kElemNodes> n{}, dr{}, dz{};
  double r = 0, det = 0;
};
Q2Point q2_point(const std::array<Node, kElemNodes>& x, double xi, double eta);

// Per-parameter local matrices of one element (the split of eqs 234, 242, 245):
//   k[c_ij]  = ∫ B_uᵀ ∂cE/∂c_ij B_u dV                        (eq. 74)
//   k[e_k]   = ∫ B_uᵀ (∂e/∂e_k)ᵀ B_φ dV, placed in both uφ and φu blocks (eq. 75)
//   k[eps_k] = −∫ B_φᵀ ∂εS/∂ε_k B_φ dV, seed sign of K_ΦΦ         (eq. 76)
//   m        = ∫ N_uᵀ N_u dV (unit density; u-block only)          (eq. 73)
struct ElementSplit {
  std::array<ElementMatrix, kNumMaterialParams> k;
  ElementMatrix m;
};

// `gauss_points` per direction (3 integrates the mass matrix exactly; the 1/r
// hoop terms are smooth over the thin wall, see tests/model/test_element.cpp).
void element_split(const std::array<Node, kElemNodes>& x, int gauss_points, ElementSplit& out);

}  // namespace piezo::model
