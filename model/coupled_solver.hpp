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
// every symmetric ordering; SimplicialLDLT is used, with SparseLU as fallback.
#include <Eigen/SparseCholesky>
#include <Eigen/SparseLU>
#include <memory>
#include <span>
#include <vector>

#include "model/tube_model.hpp"

namespace piezo::model {

enum class Electrodes { short_circuit, open_circuit };

class CoupledFactor {
 public:
  explicit CoupledFactor(const TubeModel& model);

  // Factorises K(w) − σ(M + f·ΔM) with the electrode grounded (short_circuit)
  // or free, and the DOFs in `clamped` fixed; f = end_mass_fraction (end-face
  // mass loading, model/end_mass.hpp). Returns false (status, not exception)
  // if the matrix is numerically singular.
  bool factorize(const MaterialWeights& w, double sigma, Electrodes electrodes,
                 std::span<const int> clamped = {}, double end_mass_fraction = 0.0);
  // x = A_c⁻¹ rhs (A_c the constrained matrix); rhs at constrained DOFs gives x there.
  void solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& x) const;
  // Charge on the electrode for V = 1 (constrained DOFs other than V at zero),
  // with x the full solution: Q = −(A x)_V  (eq. 72, G_V = −Q).
  double charge_for_unit_voltage(const MaterialWeights& w, std::span<const int> clamped,
                                 Eigen::VectorXd* x_out = nullptr);
  // The unconstrained combined matrix of the last factorize().
  const SpMat& matrix() const { return a_; }
  int size() const { return n_; }

 private:
  void constrain(int dof, SpMat& m) const;
  const TubeModel* model_;
  int n_ = 0;
  SpMat a_, ac_;
  Eigen::SimplicialLDLT<SpMat, Eigen::Lower, Eigen::AMDOrdering<int>> ldlt_;
  std::unique_ptr<Eigen::SparseLU<SpMat>> lu_;  // fallback, analysed lazily
  bool analysed_ = false, use_lu_ = false;
};

}  // namespace piezo::model
