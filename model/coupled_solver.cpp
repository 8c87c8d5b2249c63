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

void CoupledFactor::analyse() {
  // AMD on the pattern (values do not matter), as SimplicialLDLT<AMD> finds it.
  Eigen::SimplicialLDLT<SpMat, Eigen::Lower, Eigen::AMDOrdering<int>> amd;
  amd.analyzePattern(a_);
  perm_ = amd.permutationP();
  perm_inv_ = amd.permutationPinv();
  // The permuted upper triangle by Eigen's own assignment (its entries in the
  // order SimplicialLDLT<AMD> builds them), each value the 1-based position of
  // its source in a_ (exact in a double): the gather map.
  SpMat idx = a_;
  for (Eigen::Index k = 0; k < idx.nonZeros(); ++k) idx.valuePtr()[k] = static_cast<double>(k + 1);
  ap_.resize(n_, n_);
  ap_.selfadjointView<Eigen::Upper>() = idx.selfadjointView<Eigen::Lower>().twistedBy(perm_);
  ap_.makeCompressed();
  const auto nnz = static_cast<std::size_t>(ap_.nonZeros());
  src_.resize(nnz);
  // a_'s entry positions → their (row, column), to list each DOF's entries.
  std::vector<int> row_of(static_cast<std::size_t>(a_.nonZeros())), col_of(row_of.size());
  for (int c = 0; c < a_.outerSize(); ++c)
    for (int p = a_.outerIndexPtr()[c]; p < a_.outerIndexPtr()[c + 1]; ++p) {
      row_of[static_cast<std::size_t>(p)] = a_.innerIndexPtr()[p];
      col_of[static_cast<std::size_t>(p)] = c;
    }
  std::vector<int> count(static_cast<std::size_t>(n_) + 1, 0);
  diag_.assign(static_cast<std::size_t>(n_), -1);
  for (std::size_t k = 0; k < nnz; ++k) {
    const int s = static_cast<int>(ap_.valuePtr()[k]) - 1;
    if (s < 0 || s >= a_.nonZeros()) throw std::logic_error("CoupledFactor: permutation map out of range");
    src_[k] = s;
    const int r = row_of[static_cast<std::size_t>(s)], c = col_of[static_cast<std::size_t>(s)];
    ++count[static_cast<std::size_t>(r) + 1];
    if (c != r) ++count[static_cast<std::size_t>(c) + 1];
    else diag_[static_cast<std::size_t>(r)] = static_cast<int>(k);
  }
  for (int d = 0; d < n_; ++d) {
    if (diag_[static_cast<std::size_t>(d)] < 0)
      throw std::logic_error("CoupledFactor: the pattern has no diagonal entry for a DOF");
    count[static_cast<std::size_t>(d) + 1] += count[static_cast<std::size_t>(d)];
  }
  touch_begin_ = count;
  touch_.resize(static_cast<std::size_t>(count.back()));
  for (std::size_t k = 0; k < nnz; ++k) {
    const int r = row_of[static_cast<std::size_t>(src_[k])], c = col_of[static_cast<std::size_t>(src_[k])];
    touch_[static_cast<std::size_t>(count[static_cast<std::size_t>(r)]++)] = static_cast<int>(k);
    if (c != r) touch_[static_cast<std::size_t>(count[static_cast<std::size_t>(c)]++)] = static_cast<int>(k);
  }
  ldlt_.analyzePattern(ap_);  // natural order, upper: the factorisation reads ap_ itself
  analysed_ = true;
}

bool CoupledFactor::factorize(const MaterialWeights& w, double sigma, Electrodes electrodes,
                              std::span<const int> clamped, double end_mass_fraction) {
  model_->system().combine(w, sigma, a_, end_mass_fraction);
  if (!analysed_) analyse();
  const double* av = a_.valuePtr();
  double* pv = ap_.valuePtr();
  for (std::size_t k = 0; k < src_.size(); ++k) pv[k] = av[src_[k]];
  // The constraints as constrain() applies them to A (row and column zero,
  // diagonal one), on the permuted triangle's entries of each DOF.
  auto fix = [&](int dof) {
    if (dof < 0 || dof >= n_) throw std::invalid_argument("CoupledFactor: constrained DOF out of range");
    const auto d = static_cast<std::size_t>(dof);
    for (int t = touch_begin_[d]; t < touch_begin_[d + 1]; ++t) pv[touch_[static_cast<std::size_t>(t)]] = 0.0;
    pv[diag_[d]] = 1.0;
  };
  if (electrodes == Electrodes::short_circuit) fix(model_->dofs().electrode());
  for (int d : clamped) fix(d);
  ldlt_.factorize(ap_);
  use_lu_ = ldlt_.info() != Eigen::Success;
  if (!use_lu_) inv_d_ = ldlt_.vectorD().cwiseInverse();
  if (use_lu_) {
    ac_ = a_;
    if (electrodes == Electrodes::short_circuit) constrain(model_->dofs().electrode(), ac_);
    for (int d : clamped) constrain(d, ac_);
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
  if (use_lu_) {
    x = lu_->solve(rhs);
    return;
  }
  // SimplicialLDLT<AMD>::solve's steps — P b, L⁻¹, D⁻¹, L⁻ᵀ, P⁻¹ — on the
  // factor's arrays (L unit lower, its strict part stored by columns): the
  // Lanczos op's solve is a third of a port model, and Eigen's generic sparse
  // triangular solve pays an iterator and a zero test per column.
  const SpMat& l = ldlt_.matrixL().nestedExpression();
  const int* outer = l.outerIndexPtr();
  const int* inner = l.innerIndexPtr();
  const double* val = l.valuePtr();
  const int* p = perm_.indices().data();
  const double* b = rhs.data();
  x.resize(n_);
  double* y = x.data();
  thread_local std::vector<double> work;  // (a factor may be shared by threads: reduced_port's)
  work.resize(static_cast<std::size_t>(n_));
  double* z = work.data();
  for (int i = 0; i < n_; ++i) z[p[i]] = b[i];
  for (int j = 0; j < n_; ++j) {
    const double zj = z[j];
    for (int q = outer[j]; q < outer[j + 1]; ++q) z[inner[q]] -= val[q] * zj;
  }
  const double* inv_d = inv_d_.data();
  for (int j = 0; j < n_; ++j) z[j] *= inv_d[j];
  for (int j = n_ - 1; j >= 0; --j) {
    double s = z[j];
    for (int q = outer[j]; q < outer[j + 1]; ++q) s -= val[q] * z[inner[q]];
    z[j] = s;
  }
  for (int i = 0; i < n_; ++i) y[i] = z[p[i]];
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
  model_->system().combine(w, 0.0, a_);
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
