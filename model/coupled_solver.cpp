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

void CoupledFactor::combine(const MaterialWeights& w, double sigma, double end_mass_fraction) {
  // (σ = 0: the mass does not enter, whatever its loading.)
  const double f = sigma == 0.0 ? 0.0 : end_mass_fraction;
  if (combined_ && w == combined_w_ && sigma == combined_sigma_ && f == combined_f_) return;
  factored_ = false;  // a_ changes under the factor
  model_->system().combine(w, sigma, a_, f);
  combined_ = true;
  combined_w_ = w;
  combined_sigma_ = sigma;
  combined_f_ = f;
}

bool CoupledFactor::factorize(const MaterialWeights& w, double sigma, Electrodes electrodes,
                              std::span<const int> clamped, double end_mass_fraction) {
  combine(w, sigma, end_mass_fraction);
  if (!sky_.analysed()) sky_.analyse(a_);
  const int electrode = electrodes == Electrodes::short_circuit ? model_->dofs().electrode() : -1;
  if (factored_ && electrode == factored_electrode_ &&
      std::equal(clamped.begin(), clamped.end(), factored_clamped_.begin(), factored_clamped_.end()))
    return true;
  factored_ = false;
  use_lu_ = !sky_.factorize(a_.valuePtr(), clamped, electrode);
  if (use_lu_) {
    ac_ = a_;
    if (electrode >= 0) constrain(electrode, ac_);
    for (int d : clamped) constrain(d, ac_);
    if (!lu_) {
      lu_ = std::make_unique<Eigen::SparseLU<SpMat>>();
      lu_->analyzePattern(ac_);
    }
    lu_->factorize(ac_);
    if (lu_->info() != Eigen::Success) return false;
  }
  factored_ = true;
  factored_electrode_ = electrode;
  factored_clamped_.assign(clamped.begin(), clamped.end());
  return true;
}

void CoupledFactor::solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& x) const {
  if (use_lu_) {
    x = lu_->solve(rhs);
    return;
  }
  x.resize(n_);
  sky_.solve(rhs.data(), x.data());
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

double CoupledFactor::charge_for_unit_voltage_u_clamped(const MaterialWeights& w, Eigen::VectorXd* x_out) {
  combine(w, 0.0, 0.0);
  const int nu = model_->n_u(), v = model_->dofs().electrode(), ni = n_ - nu - 1;
  if (v != n_ - 1 || ni < 1) throw std::logic_error("CoupledFactor: expected [U; Φ_int; V] DOF order");
  if (kii_src_.empty()) {  // the block's pattern and its map into a_, once
    std::vector<Eigen::Triplet<double>> t;
    std::vector<int> pos;
    for (int c = nu; c < v; ++c)
      for (int p = a_.outerIndexPtr()[c]; p < a_.outerIndexPtr()[c + 1]; ++p)
        if (const int r = a_.innerIndexPtr()[p]; r >= nu && r < v) {
          t.emplace_back(r - nu, c - nu, static_cast<double>(pos.size() + 1));
          pos.push_back(p);
        }
    kii_.resize(ni, ni);
    kii_.setFromTriplets(t.begin(), t.end());
    kii_.makeCompressed();
    kii_src_.resize(static_cast<std::size_t>(kii_.nonZeros()));
    for (Eigen::Index k = 0; k < kii_.nonZeros(); ++k)
      kii_src_[static_cast<std::size_t>(k)] = pos[static_cast<std::size_t>(kii_.valuePtr()[k]) - 1];
    kii_ldlt_.analyzePattern(kii_);
  }
  for (std::size_t k = 0; k < kii_src_.size(); ++k) kii_.valuePtr()[k] = a_.valuePtr()[kii_src_[k]];
  kii_ldlt_.factorize(kii_);
  if (kii_ldlt_.info() != Eigen::Success) {  // the whole system's path (its LU fallback)
    std::vector<int> all_u(static_cast<std::size_t>(nu));
    for (int i = 0; i < nu; ++i) all_u[static_cast<std::size_t>(i)] = i;
    return charge_for_unit_voltage(w, all_u, x_out);
  }
  const Eigen::VectorXd col_v = a_.col(v);
  const Eigen::VectorXd phi_i = kii_ldlt_.solve(-col_v.segment(nu, ni));
  Eigen::VectorXd x = Eigen::VectorXd::Zero(n_);
  x.segment(nu, ni) = phi_i;
  x[v] = 1.0;
  const double q = -col_v.dot(x);  // A symmetric: (A x)_V = A(:,V)·x
  if (x_out) *x_out = std::move(x);
  return q;
}

}  // namespace piezo::model
