#pragma once
// update/: the material model classes the updater works in and the updating
// coordinates of the three phases of seed §6.4.
//
// Both classes are described by the four sensitive d-form constants of a thin
// radially poled tube (YE11, nu12, d31, epsT33; seed §6.4.3, Appendix C):
//  * isotropic      — the physical simplification, eqs 218-219 (sE13 = sE12,
//                     sE33 = sE11, sE44 = sE66, epsT11 = d33 = d15 = 0);
//  * transversely_isotropic — the full 4mm material with the six insensitive
//                     constants sE13, sE33, sE44, d33, d15, epsT11 held at
//                     their nominal values.
// Updating coordinates q = (c1, c2, epsT33, a):
//  * isotropic: c1 = cE11, c2 = cE12 of the 3-D isotropic stiffness (eqs
//    222-223, K_UU exactly linear in them, eqs 238-241) and a = e31²/εS33
//    (eq. 249) with e31 = d31(c1 + c2) (228), εS33 = εT33 − 2 d31²(c1 + c2) (233);
//  * transversely isotropic: c1, c2 the reduced (plane-stress) stiffnesses
//    c̃E11 = sE11/((sE11+sE12)(sE11−sE12)), c̃E12 = −sE12/(…) (eqs 20-21) and
//    a the reduced e31²/εS33 (eqs 23-24, 211-212). K_UU is not linear in them.
// In both, C = c1 + c2 and eqs 251-253 give εS33, e31, d31 from (C, εT33, a).
#include <string>

#include "model/material.hpp"

namespace piezo::update {

enum class ModelClass { isotropic, transversely_isotropic };
const char* to_string(ModelClass c);

// The four sensitive constants in engineering form (Table 4 of the seed).
using TubeParams = model::IsotropicPiezoParams;

struct Coordinates {
  double c1 = 0, c2 = 0;  // N/m²
  double eps_t33 = 0;     // F/m
  double a = 0;           // e31²/εS33, N²/(C·… ) = (C/m²)²/(F/m)
};

// The e-form constants reported next to the engineering ones (Table 5).
struct EFormSummary {
  double c_e11 = 0, c_e12 = 0;  // the class's c1, c2
  double e31 = 0;               // eq. 252
  double eps_s33 = 0;           // eq. 251
};

class MaterialClass {
 public:
  static MaterialClass isotropic();
  // `nominal` supplies sE13, sE33, sE44, d33, d15, epsT11.
  static MaterialClass transversely_isotropic(const model::PiezoMaterialD& nominal);

  ModelClass kind() const { return kind_; }

  // Full d-/e-form material for the four parameters. Throws std::invalid_argument
  // for non-physical values (e.g. negative clamped permittivity).
  model::PiezoMaterialD d_form(const TubeParams& p) const;
  model::PiezoMaterialE e_form(const TubeParams& p) const { return model::to_e_form(d_form(p)); }

  Coordinates coordinates(const TubeParams& p) const;
  // Inverse; `d31_sign` (±1) picks the root of e31 = ±sqrt(a εS33) (eq. 252 takes −).
  TubeParams params(const Coordinates& q, double d31_sign = -1.0) const;
  EFormSummary e_summary(const Coordinates& q, double d31_sign = -1.0) const;

 private:
  ModelClass kind_ = ModelClass::isotropic;
  model::PiezoMaterialD nominal_;
};

// a = d31² C² / (εT33 − 2 d31² C)  (eqs 208 + 228 + 233, or 211-212 reduced).
double a_from_d31(double d31, double c_sum, double eps_t33);
// εS33* = C εT33/(C + 2a) (251), e31* = ∓sqrt(a εS33*) (252), d31* = e31*/C (253).
double eps_s33_from(double c_sum, double eps_t33, double a);
double d31_from_a(double c_sum, double eps_t33, double a, double d31_sign = -1.0);

}  // namespace piezo::update
