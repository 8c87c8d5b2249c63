#pragma once
// Factorisation of the coupled electro-mechanical system A = K(material) − σM
// over x = [U; Φ_int; V] with the electrical and mechanical conditions applied
// by replacing constrained rows/columns with identity rows (same pattern, so
// the symbolic analysis is done once per mesh and reused for every material,
// shift and boundary condition). Internal potentials are always free (zero
// charge), which is the static condensation of Φ_int; the electrode DOF is
// either grounded (short circuit) or free with zero net charge (open circuit,
// eq. 92).
//
// A is symmetric indefinite (K_ΦΦ < 0). For σ < 0 (or σ = 0 with the rigid
// z-translation clamped) it is quasi-definite, for which an LDLᵀ exists for
// every symmetric ordering; an envelope LDLᵀ (model/skyline_ldlt.hpp, its
// reverse Cuthill–McKee ordering found once per mesh) is used, with SparseLU
// as fallback. Each factorisation scatters the combined values into the
// envelope and applies the constraints there (no copy of the whole matrix).
#include <Eigen/SparseCholesky>
#include <Eigen/SparseLU>
#include <memory>
#include <span>
#include <vector>

#include "model/skyline_ldlt.hpp"
#include "model/tube_model.hpp"

namespace piezo::model {

enum class Electrodes { short_circuit, open_circuit };

class CoupledFactor {
 public:
  explicit CoupledFactor(const TubeModel& model);

  // Factorises K(w) − σ(M + f·ΔM) with the electrode grounded (short_circuit)
  // or free, and the DOFs in `clamped` fixed; f = end_mass_fraction (end-face
  // mass loading, model/end_mass.hpp). Returns false (status, not exception)
  // if the matrix is numerically singular. The same matrix and conditions as
  // the last successful call: nothing to do (the factor is kept).
  bool factorize(const MaterialWeights& w, double sigma, Electrodes electrodes,
                 std::span<const int> clamped = {}, double end_mass_fraction = 0.0);
  // x = A_c⁻¹ rhs (A_c the constrained matrix); rhs at constrained DOFs gives x there.
  void solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& x) const;
  // Charge on the electrode for V = 1 (constrained DOFs other than V at zero),
  // with x the full solution: Q = −(A x)_V  (eq. 72, G_V = −Q).
  double charge_for_unit_voltage(const MaterialWeights& w, std::span<const int> clamped,
                                 Eigen::VectorXd* x_out = nullptr);
  // The same with every U DOF clamped (the clamped capacitance C0): only the
  // interior potentials are unknown, K_ii Φ_i = −K_iV, solved on that block
  // alone (a sparse LDLᵀ of the potentials' block, analysed once) instead of
  // the whole system with identity rows. σ = 0, V grounded but lifted to 1.
  double charge_for_unit_voltage_u_clamped(const MaterialWeights& w, Eigen::VectorXd* x_out = nullptr);
  // The unconstrained combined matrix of the last factorize().
  const SpMat& matrix() const { return a_; }
  int size() const { return n_; }

 private:
  void constrain(int dof, SpMat& m) const;
  // a_ ← K(w) − σ(M + f·ΔM), unless a_ already holds it (a port model's
  // static solve and clamped capacitance share σ = 0).
  void combine(const MaterialWeights& w, double sigma, double end_mass_fraction);
  bool combined_ = false;
  MaterialWeights combined_w_{};
  double combined_sigma_ = 0, combined_f_ = 0;
  // What the factor holds: a_'s values (combine) with these DOFs constrained.
  // A repeat (a port model's static solve, then its Lanczos at σ = 0 on a
  // model without a rigid mode) reuses it.
  bool factored_ = false;
  int factored_electrode_ = -1;
  std::vector<int> factored_clamped_;
  const TubeModel* model_;
  int n_ = 0;
  SpMat a_, ac_;  // ac_: the constrained matrix, made only for the LU fallback
  SkylineLdlt sky_;
  std::unique_ptr<Eigen::SparseLU<SpMat>> lu_;  // fallback, analysed lazily
  // The interior potentials' block K_ii (charge_for_unit_voltage_u_clamped).
  SpMat kii_;
  std::vector<int> kii_src_;  // kii_'s entry k holds a_'s value kii_src_[k]
  Eigen::SimplicialLDLT<SpMat, Eigen::Lower, Eigen::AMDOrdering<int>> kii_ldlt_;
  bool use_lu_ = false;
};

}  // namespace piezo::model
