#include "update/parametrization.hpp"

#include <cmath>
#include <stdexcept>

namespace piezo::update {

const char* to_string(ModelClass c) {
  return c == ModelClass::isotropic ? "isotropic" : "transversely_isotropic";
}

MaterialClass MaterialClass::isotropic() { return MaterialClass{}; }

MaterialClass MaterialClass::transversely_isotropic(const model::PiezoMaterialD& nominal) {
  MaterialClass m;
  m.kind_ = ModelClass::transversely_isotropic;
  m.nominal_ = nominal;
  return m;
}

model::PiezoMaterialD MaterialClass::d_form(const TubeParams& p) const {
  if (kind_ == ModelClass::isotropic) return model::to_d_form(p);
  const char* fn = "MaterialClass::d_form";
  if (!(p.y_e11 > 0) || !std::isfinite(p.y_e11))
    throw std::invalid_argument(std::string(fn) + ": YE11 must be > 0");
  if (!(p.eps_t33 > 0) || !std::isfinite(p.eps_t33))
    throw std::invalid_argument(std::string(fn) + ": epsT33 must be > 0");
  if (!std::isfinite(p.nu12) || !std::isfinite(p.d31))
    throw std::invalid_argument(std::string(fn) + ": nu12 and d31 must be finite");
  model::PiezoMaterialD m = nominal_;
  m.s_e11 = 1.0 / p.y_e11;
  m.s_e12 = -p.nu12 / p.y_e11;
  m.d31 = p.d31;
  m.eps_t33 = p.eps_t33;
  return m;
}

double a_from_d31(double d31, double c_sum, double eps_t33) {
  const double x = d31 * d31 * c_sum;
  if (!(eps_t33 - 2.0 * x > 0))
    throw std::invalid_argument("a_from_d31: epsS33 = epsT33 − 2 d31² C is not positive");
  return x * c_sum / (eps_t33 - 2.0 * x);
}

double eps_s33_from(double c_sum, double eps_t33, double a) {
  if (!(c_sum > 0) || !(a >= 0) || !(eps_t33 > 0))
    throw std::invalid_argument("eps_s33_from: needs C > 0, a >= 0, epsT33 > 0");
  return c_sum * eps_t33 / (c_sum + 2.0 * a);  // eq. 251
}

double d31_from_a(double c_sum, double eps_t33, double a, double d31_sign) {
  const double e31 = std::sqrt(a * eps_s33_from(c_sum, eps_t33, a));  // eq. 252 (magnitude)
  return (d31_sign < 0 ? -e31 : e31) / c_sum;                         // eq. 253
}

Coordinates MaterialClass::coordinates(const TubeParams& p) const {
  Coordinates q;
  const double y = p.y_e11, nu = p.nu12;
  if (kind_ == ModelClass::isotropic) {
    const double f = y / ((1.0 + nu) * (1.0 - 2.0 * nu));
    q.c1 = (1.0 - nu) * f;  // eq. 222
    q.c2 = nu * f;          // eq. 223
  } else {
    const double s11 = 1.0 / y, s12 = -nu / y;
    const double det = (s11 + s12) * (s11 - s12);
    q.c1 = s11 / det;   // eq. 20
    q.c2 = -s12 / det;  // eq. 21
  }
  if (!(q.c1 > 0) || !(q.c1 + q.c2 > 0) || !(q.c1 - q.c2 > 0))
    throw std::invalid_argument("MaterialClass::coordinates: non-physical elastic constants");
  q.eps_t33 = p.eps_t33;
  q.a = a_from_d31(p.d31, q.c1 + q.c2, p.eps_t33);
  return q;
}

TubeParams MaterialClass::params(const Coordinates& q, double d31_sign) const {
  if (!(q.c1 > 0) || !(q.c1 + q.c2 > 0) || !(q.c1 - q.c2 > 0) || !std::isfinite(q.c1 + q.c2))
    throw std::invalid_argument("MaterialClass::params: non-physical stiffnesses c1, c2");
  TubeParams p;
  if (kind_ == ModelClass::isotropic) {
    p.nu12 = q.c2 / (q.c1 + q.c2);                                    // eq. 254
    p.y_e11 = q.c2 / p.nu12 * (1.0 + p.nu12) * (1.0 - 2.0 * p.nu12);  // eq. 255
    if (q.c2 == 0) p.y_e11 = q.c1;                                    // nu = 0 limit
  } else {
    p.nu12 = q.c2 / q.c1;                          // −sE12/sE11
    p.y_e11 = (q.c1 * q.c1 - q.c2 * q.c2) / q.c1;  // 1/sE11
  }
  p.eps_t33 = q.eps_t33;
  p.d31 = d31_from_a(q.c1 + q.c2, q.eps_t33, q.a, d31_sign);
  return p;
}

EFormSummary MaterialClass::e_summary(const Coordinates& q, double d31_sign) const {
  EFormSummary s;
  s.c_e11 = q.c1;
  s.c_e12 = q.c2;
  s.eps_s33 = eps_s33_from(q.c1 + q.c2, q.eps_t33, q.a);
  s.e31 = (d31_sign < 0 ? -1.0 : 1.0) * std::sqrt(q.a * s.eps_s33);
  return s;
}

}  // namespace piezo::update
