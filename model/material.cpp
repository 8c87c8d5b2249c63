#include "model/material.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <cmath>
#include <stdexcept>
#include <string>

namespace piezo::model {

namespace {

[[noreturn]] void fail(const char* fn, const std::string& what) {
  throw std::invalid_argument(std::string(fn) + ": " + what);
}

bool finite_all(std::initializer_list<double> v) {
  for (double x : v)
    if (!std::isfinite(x)) return false;
  return true;
}

}  // namespace

void MaterialLosses::validate() const {
  if (!(qm > 0)) fail("MaterialLosses::validate", "qm must be > 0 (use infinity for no loss)");
  if (!(tan_delta >= 0 && tan_delta < 1))
    fail("MaterialLosses::validate", "tan_delta must be in [0, 1)");
}

PiezoMatrices to_matrices(const PiezoMaterialD& m) {
  PiezoMatrices r;
  auto& s = r.elastic;
  s.setZero();
  s(0, 0) = s(1, 1) = m.s_e11;
  s(0, 1) = s(1, 0) = m.s_e12;
  s(0, 2) = s(2, 0) = s(1, 2) = s(2, 1) = m.s_e13;
  s(2, 2) = m.s_e33;
  s(3, 3) = s(4, 4) = m.s_e44;
  s(5, 5) = 2.0 * (m.s_e11 - m.s_e12);  // sE66
  auto& d = r.piezo;                     // eq. 7
  d.setZero();
  d(0, 4) = d(1, 3) = m.d15;
  d(2, 0) = d(2, 1) = m.d31;
  d(2, 2) = m.d33;
  r.dielectric.setZero();
  r.dielectric(0, 0) = r.dielectric(1, 1) = m.eps_t11;
  r.dielectric(2, 2) = m.eps_t33;
  return r;
}

PiezoMatrices to_matrices(const PiezoMaterialE& m) {
  PiezoMatrices r;
  auto& c = r.elastic;  // eq. 3
  c.setZero();
  c(0, 0) = c(1, 1) = m.c_e11;
  c(0, 1) = c(1, 0) = m.c_e12;
  c(0, 2) = c(2, 0) = c(1, 2) = c(2, 1) = m.c_e13;
  c(2, 2) = m.c_e33;
  c(3, 3) = c(4, 4) = m.c_e44;
  c(5, 5) = 0.5 * (m.c_e11 - m.c_e12);  // cE66
  auto& e = r.piezo;                     // eq. 4
  e.setZero();
  e(0, 4) = e(1, 3) = m.e15;
  e(2, 0) = e(2, 1) = m.e31;
  e(2, 2) = m.e33;
  r.dielectric.setZero();
  r.dielectric(0, 0) = r.dielectric(1, 1) = m.eps_s11;
  r.dielectric(2, 2) = m.eps_s33;
  return r;
}

namespace {
// Eqs 8-12; `checked`: sE positive definite (LLT) and εS ≥ 0 required, else
// any invertible sE (LU) and whatever εS follows.
PiezoMaterialE e_form_of(const PiezoMaterialD& m, bool checked) {
  const char* fn = checked ? "to_e_form" : "to_e_form_unchecked";
  if (!finite_all({m.s_e11, m.s_e12, m.s_e13, m.s_e33, m.s_e44, m.d31, m.d33, m.d15, m.eps_t11,
                   m.eps_t33}))
    fail(fn, "non-finite constant");
  auto dm = to_matrices(m);
  Eigen::Matrix<double, 6, 6> c;
  if (checked) {
    Eigen::LLT<Eigen::Matrix<double, 6, 6>> llt(dm.elastic);
    if (llt.info() != Eigen::Success) fail(fn, "compliance sE is not positive definite");
    c = llt.solve(Eigen::Matrix<double, 6, 6>::Identity());  // eq 8
  } else {
    const Eigen::FullPivLU<Eigen::Matrix<double, 6, 6>> lu(dm.elastic);
    if (!lu.isInvertible()) fail(fn, "compliance sE is singular");
    c = lu.inverse();
  }
  const Eigen::Matrix<double, 3, 6> e = dm.piezo * c;                                        // eq 9
  const Eigen::Matrix3d eps_s = dm.dielectric - dm.piezo * c * dm.piezo.transpose();        // eq 11
  PiezoMaterialE r;
  r.c_e11 = c(0, 0);
  r.c_e12 = c(0, 1);
  r.c_e13 = c(0, 2);
  r.c_e33 = c(2, 2);
  r.c_e44 = c(3, 3);
  r.e31 = e(2, 0);
  r.e33 = e(2, 2);
  r.e15 = e(0, 4);
  // Round-off can leave −1e-30 where the exact value is 0 (isotropic class).
  const double tiny = 1e-12 * m.eps_t33;
  r.eps_s11 = std::abs(eps_s(0, 0)) < tiny ? 0.0 : eps_s(0, 0);
  r.eps_s33 = eps_s(2, 2);
  if (checked && (r.eps_s11 < 0 || !(r.eps_s33 > 0)))
    fail(fn, "clamped permittivity epsS = epsT − d·cE·dᵀ is negative (coupling factor > 1)");
  return r;
}
}  // namespace

PiezoMaterialE to_e_form(const PiezoMaterialD& m) { return e_form_of(m, true); }

PiezoMaterialE to_e_form_unchecked(const PiezoMaterialD& m) { return e_form_of(m, false); }

PiezoMaterialD to_d_form(const PiezoMaterialE& m) {
  const char* fn = "to_d_form";
  auto em = to_matrices(m);
  Eigen::LLT<Eigen::Matrix<double, 6, 6>> llt(em.elastic);
  if (llt.info() != Eigen::Success) fail(fn, "stiffness cE is not positive definite");
  const Eigen::Matrix<double, 6, 6> s = llt.solve(Eigen::Matrix<double, 6, 6>::Identity());
  const Eigen::Matrix<double, 3, 6> d = em.piezo * s;
  const Eigen::Matrix3d eps_t = em.dielectric + em.piezo * s * em.piezo.transpose();  // eq 12
  PiezoMaterialD r;
  r.s_e11 = s(0, 0);
  r.s_e12 = s(0, 1);
  r.s_e13 = s(0, 2);
  r.s_e33 = s(2, 2);
  r.s_e44 = s(3, 3);
  r.d31 = d(2, 0);
  r.d33 = d(2, 2);
  r.d15 = d(0, 4);
  r.eps_t11 = eps_t(0, 0);
  r.eps_t33 = eps_t(2, 2);
  return r;
}

EngineeringConstants engineering_constants(const PiezoMaterialD& m) {
  if (!(m.s_e11 > 0 && m.s_e33 > 0 && m.s_e44 > 0))
    fail("engineering_constants", "sE11, sE33 and sE44 must be > 0");
  EngineeringConstants ec;
  ec.y_e11 = 1.0 / m.s_e11;
  ec.y_e33 = 1.0 / m.s_e33;
  ec.nu12 = -m.s_e12 * ec.y_e11;
  ec.nu13 = -m.s_e13 * ec.y_e33;  // seed eq. 13 writes sE13 = −nu13/YE33
  ec.g = 1.0 / m.s_e44;
  return ec;
}

PiezoMaterialD with_engineering_constants(const PiezoMaterialD& base,
                                          const EngineeringConstants& ec) {
  if (!(ec.y_e11 > 0 && ec.y_e33 > 0 && ec.g > 0))
    fail("with_engineering_constants", "YE11, YE33 and G must be > 0");
  PiezoMaterialD m = base;
  m.s_e11 = 1.0 / ec.y_e11;
  m.s_e12 = -ec.nu12 / ec.y_e11;
  m.s_e13 = -ec.nu13 / ec.y_e33;
  m.s_e33 = 1.0 / ec.y_e33;
  m.s_e44 = 1.0 / ec.g;
  return m;
}

PiezoMaterialD to_d_form(const IsotropicPiezoParams& p) {
  const char* fn = "to_d_form(IsotropicPiezoParams)";
  if (!(p.y_e11 > 0) || !std::isfinite(p.y_e11)) fail(fn, "YE11 must be > 0");
  if (!(p.nu12 > -1.0 && p.nu12 < 0.5)) fail(fn, "nu12 must lie in (−1, 0.5)");
  if (!(p.eps_t33 > 0) || !std::isfinite(p.eps_t33)) fail(fn, "epsT33 must be > 0");
  if (!std::isfinite(p.d31)) fail(fn, "d31 must be finite");
  PiezoMaterialD m;
  m.s_e11 = 1.0 / p.y_e11;
  m.s_e12 = -p.nu12 / p.y_e11;
  m.s_e13 = m.s_e12;                        // eq. 218
  m.s_e33 = m.s_e11;                        // eq. 218
  m.s_e44 = 2.0 * (m.s_e11 - m.s_e12);      // sE44 = sE66, eq. 218
  m.d31 = p.d31;
  m.d33 = m.d15 = m.eps_t11 = 0.0;          // eq. 219
  m.eps_t33 = p.eps_t33;
  return m;
}

IsotropicPiezoParams isotropic_params(const PiezoMaterialD& m) {
  if (!(m.s_e11 > 0)) fail("isotropic_params", "sE11 must be > 0");
  return {1.0 / m.s_e11, -m.s_e12 / m.s_e11, m.d31, m.eps_t33};
}

void validate_finite(const PiezoMaterialE& m, const char* caller) {
  const std::string fn = std::string(caller) + " (material)";
  if (!finite_all({m.c_e11, m.c_e12, m.c_e13, m.c_e33, m.c_e44, m.e31, m.e33, m.e15, m.eps_s11,
                   m.eps_s33}))
    fail(fn.c_str(), "non-finite constant");
}

void validate(const PiezoMaterialE& m, const char* caller) {
  const std::string fn = std::string(caller) + " (material)";
  validate_finite(m, caller);
  Eigen::Matrix4d c;  // axisymmetric block, strains (1, 2, 3, 5)
  c << m.c_e11, m.c_e12, m.c_e13, 0, m.c_e12, m.c_e11, m.c_e13, 0, m.c_e13, m.c_e13, m.c_e33, 0, 0,
      0, 0, m.c_e44;
  Eigen::LLT<Eigen::Matrix4d> llt(c);
  if (llt.info() != Eigen::Success) fail(fn.c_str(), "stiffness cE is not positive definite");
  if (!(m.eps_s33 > 0)) fail(fn.c_str(), "epsS33 must be > 0");
  if (m.eps_s11 < 0) fail(fn.c_str(), "epsS11 must be >= 0");
}

MaterialWeights weights(const PiezoMaterialE& m) {
  return {m.c_e11, m.c_e12, m.c_e13, m.c_e33, m.c_e44, m.e31, m.e33, m.e15, m.eps_s11, m.eps_s33};
}

const char* param_name(MaterialParam p) {
  static constexpr const char* names[kNumMaterialParams] = {
      "cE11", "cE12", "cE13", "cE33", "cE44", "e31", "e33", "e15", "epsS11", "epsS33"};
  return names[static_cast<int>(p)];
}

}  // namespace piezo::model
