#pragma once
// Piezoceramic material of the 4mm (C4v, transversely isotropic) class, seed §2.2.
// IEEE notation: 3 = poling direction (= radial for the tube), 1-2 the isotropic
// plane, Voigt shear 4 = 23, 5 = 13, 6 = 12. Two equivalent forms:
//   d-form (eqs 5-7): sE, d, epsT      e-form (eqs 1-4): cE, e, epsS
// with the exact conversions cE = sE^-1 (eq 8), e = d·cE (eq 9),
// epsS = epsT − d·cE·dᵀ (eq 11), and back sE = cE^-1, d = e·sE,
// epsT = epsS + e·sE·eᵀ (eq 12). Losses are optional and carried separately.
#include <Eigen/Core>
#include <array>
#include <limits>
#include <string>

namespace piezo::model {

inline constexpr double kEps0 = 8.854187817e-12;  // F/m, as in seed Table 2

// d-form constants (SI: m²/N, C/N, F/m). sE66 = 2(sE11 − sE12) is implied.
struct PiezoMaterialD {
  double s_e11 = 0, s_e12 = 0, s_e13 = 0, s_e33 = 0, s_e44 = 0;
  double d31 = 0, d33 = 0, d15 = 0;
  double eps_t11 = 0, eps_t33 = 0;
};

// e-form constants (SI: N/m², C/m², F/m). cE66 = (cE11 − cE12)/2 is implied.
struct PiezoMaterialE {
  double c_e11 = 0, c_e12 = 0, c_e13 = 0, c_e33 = 0, c_e44 = 0;
  double e31 = 0, e33 = 0, e15 = 0;
  double eps_s11 = 0, eps_s33 = 0;
};

// Engineering elastic constants of the transversely isotropic compliance, eq. 13.
struct EngineeringConstants {
  double y_e11 = 0;  // Young's modulus in the isotropic plane
  double y_e33 = 0;  // Young's modulus along the poling axis
  double nu12 = 0;   // contraction in 2 for extension in 1
  double nu13 = 0;   // contraction in 3 for extension in 1 (sE13 = −nu13/YE33, eq. 13)
  double g = 0;      // shear modulus G = 1/sE44
};

// The isotropic-simplification model class of seed §6.4.3 (eqs 218-233): four
// parameters; sE13 = sE12, sE33 = sE11, sE44 = sE66 and epsT11 = d33 = d15 = 0.
struct IsotropicPiezoParams {
  double y_e11 = 0;
  double nu12 = 0;
  double d31 = 0;
  double eps_t33 = 0;
};

// Optional material losses. Mechanical: complex stiffness cE·(1 + j/Qm);
// dielectric: epsS·(1 − j·tanδ) (time convention e^{jωt}). Rayleigh damping
// (C = αM + βK_UU) is a property of the analysis, see model/harmonic.hpp.
struct MaterialLosses {
  double qm = std::numeric_limits<double>::infinity();  // mechanical quality factor
  double tan_delta = 0.0;                               // dielectric loss tangent
  void validate() const;
  bool lossless() const { return !(qm < std::numeric_limits<double>::infinity()) && tan_delta == 0; }
};

// Full 6×6 / 3×6 / 3×3 IEEE matrices of each form.
struct PiezoMatrices {
  Eigen::Matrix<double, 6, 6> elastic;     // sE or cE
  Eigen::Matrix<double, 3, 6> piezo;       // d or e
  Eigen::Matrix<double, 3, 3> dielectric;  // epsT or epsS
};

PiezoMatrices to_matrices(const PiezoMaterialD& m);
PiezoMatrices to_matrices(const PiezoMaterialE& m);

// Exact conversions (eqs 8-12). Throw std::invalid_argument when the elastic
// matrix is not positive definite, or the resulting permittivity is negative.
PiezoMaterialE to_e_form(const PiezoMaterialD& m);
PiezoMaterialD to_d_form(const PiezoMaterialE& m);
// The same algebra without the physical checks: any invertible sE (LU), a
// negative εS kept. Only for the seed's own non-physical perturbations
// (Appendix C: sE13 doubled, εT33 halved), reported as such. Throws for a
// singular sE or a non-finite constant.
PiezoMaterialE to_e_form_unchecked(const PiezoMaterialD& m);

EngineeringConstants engineering_constants(const PiezoMaterialD& m);
// Compliances from engineering constants (eq. 13); piezo/dielectric left as in `base`.
PiezoMaterialD with_engineering_constants(const PiezoMaterialD& base, const EngineeringConstants& ec);

// §6.4.3 model class → d-form (eqs 218-219); e-form follows from to_e_form,
// giving e31 = d31(cE11 + cE12) (228), e33 = 2 d31 cE12 (229),
// epsS33 = epsT33 − 2 d31²(cE11 + cE12) (233) and epsS11 = 0.
PiezoMaterialD to_d_form(const IsotropicPiezoParams& p);
// The four parameters of a material (YE11 = 1/sE11, nu12 = −sE12/sE11, d31, epsT33).
IsotropicPiezoParams isotropic_params(const PiezoMaterialD& m);

// Validation of the e-form used by the FE model: the axisymmetric 4×4 cE block
// positive definite, epsS33 > 0, epsS11 ≥ 0 (= 0 is the isotropic class, see
// model/README.md for why K_ΦΦ stays non-singular). Throws std::invalid_argument.
void validate(const PiezoMaterialE& m, const char* caller);
// Only that every constant is finite (ModalSolver::set_physical_checks(false)).
void validate_finite(const PiezoMaterialE& m, const char* caller);

// The ten e-form parameters in a fixed order; the split matrices of the
// assembler (seed eqs 234, 242, 245) are indexed the same way.
enum class MaterialParam : int { c11, c12, c13, c33, c44, e31, e33, e15, eps11, eps33 };
inline constexpr int kNumMaterialParams = 10;
using MaterialWeights = std::array<double, kNumMaterialParams>;
MaterialWeights weights(const PiezoMaterialE& m);
const char* param_name(MaterialParam p);

}  // namespace piezo::model
