#include "model/coupled_solver.hpp"

#include <algorithm>
#include <stdexcept>

namespace piezo::model {

CoupledFactor::CoupledFactor(const TubeModel& model)
    : model_(&model), n_(model.dofs().n_total()) {}

void CoupledFactor::constrain(int dof, SpMat& m) const {
  if (dof < 0 || dof >= n_) throw std::invalid_argument("CoupledFactor: constrained DOF out of range");
  const auto& sys = model_->system();
  const int* outer = m.outerIndexPtr();
  const int* inner = m.innerIndexPtr();
  double* val = m.valuePtr();
  int diagonal = -1;
  for (int p = outer[dof]; p < outer[dof + 1]; ++p) {
    if (inner[p] == dof) diagonal = p;
    val[p] = 0.0;                   // column dof
    val[sys.transposed(p)] = 0.0;   // row dof (symmetric pattern)
  }
  if (diagonal < 0) throw std::logic_error("CoupledFactor: the pattern has no diagonal entry for a DOF");
  val[diagonal] = 1.0;
}

bool CoupledFactor::factorize(const MaterialWeights& w, double sigma, Electrodes electrodes,
                              std::span<const int> clamped, double end_mass_fraction) {
  model_->system().combine(w, sigma, a_, end_mass_fraction);
  if (ac_.nonZeros() == a_.nonZeros() && ac_.rows() == a_.rows())  // the same pattern: the values only
    std::copy(a_.valuePtr(), a_.valuePtr() + a_.nonZeros(), ac_.valuePtr());
  else
    ac_ = a_;
  if (electrodes == Electrodes::short_circuit) constrain(model_->dofs().electrode(), ac_);
  for (int d : clamped) constrain(d, ac_);
  if (!analysed_) {
    ldlt_.analyzePattern(ac_);
    analysed_ = true;
  }
  ldlt_.factorize(ac_);
  use_lu_ = ldlt_.info() != Eigen::Success;
  if (use_lu_) {
    if (!lu_) {
      lu_ = std::make_unique<Eigen::SparseLU<SpMat>>();
      lu_->analyzePattern(ac_);
    }
    lu_->factorize(ac_);
    return lu_->info() == Eigen::Success;
  }
  return true;
}

void CoupledFactor::solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& x) const {
  if (use_lu_)
    x = lu_->solve(rhs);
  else
    x = ldlt_.solve(rhs);
}

double CoupledFactor::charge_for_unit_voltage(const MaterialWeights& w,
                                              std::span<const int> clamped,
                                              Eigen::VectorXd* x_out) {
  // Lift V = 1: rhs = −A(:, V) on the free DOFs, 1 at V, 0 at the clamped DOFs.
  if (!factorize(w, 0.0, Electrodes::short_circuit, clamped))
    throw std::runtime_error("CoupledFactor::charge_for_unit_voltage: singular system");
  const int v = model_->dofs().electrode();
  Eigen::VectorXd rhs = -Eigen::VectorXd(a_.col(v));
  for (int d : clamped) rhs[d] = 0.0;
  rhs[v] = 1.0;
  Eigen::VectorXd x;
  solve(rhs, x);
  const double q = -a_.col(v).dot(x);  // A symmetric: (A x)_V = A(:,V)·x
  if (x_out) *x_out = std::move(x);
  return q;
}

}  // namespace piezo::model
