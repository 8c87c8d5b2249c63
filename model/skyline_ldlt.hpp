#pragma once
// LDLᵀ of a symmetric sparse matrix in envelope (skyline) storage, for the
// coupled system of CoupledFactor (model/coupled_solver.hpp): the tube's
// mesh is a thin strip, so a reverse Cuthill–McKee ordering (the electrode's
// dense row and column last) gives rows of about twenty entries, and the
// factor's envelope (7049 entries on the default half tube) is hardly larger
// than the fill of a minimum-degree sparse factor (6665). Stored row by row
// and contiguous, the factorisation's and the solve's inner loops are dot
// products and AXPYs over short contiguous runs, not a sparse factor's
// scattered updates: the modal solve's 32 solves and two factorisations were
// two thirds of a port model (issue 43).
//
// No pivoting: A must be strongly factorisable, as the quasi-definite
// coupled system is for every symmetric ordering (K_UU − σM > 0, K_ΦΦ < 0).
// factorize() reports a zero or non-finite pivot; the caller falls back.
//
// Constrained DOFs (Dirichlet rows, CoupledFactor's identity rows) are
// applied on the factor's copy of the values: their row and column zero,
// their pivot one.
#include <Eigen/SparseCore>
#include <span>
#include <vector>

namespace piezo::model {

class SkylineLdlt {
 public:
  using SpMat = Eigen::SparseMatrix<double>;

  // The ordering and the envelope of `pattern` (symmetric, both triangles
  // stored, compressed, a diagonal entry in every column). A DOF whose degree
  // is above a quarter of n (the electrode) is ordered last.
  void analyse(const SpMat& pattern);
  bool analysed() const { return n_ > 0; }

  // Factorises the matrix with `values` on the analysed pattern (its value
  // array, in the pattern's storage order), the DOFs in `clamped` and
  // `extra_clamped` (−1: none) constrained. False on a zero or non-finite pivot.
  bool factorize(const double* values, std::span<const int> clamped, int extra_clamped = -1);
  // x = A_c⁻¹ b (b and x of size n; may not alias). Thread-safe on a factorised object.
  void solve(const double* b, double* x) const;

  int size() const { return n_; }
  // Entries of the factor's strict lower envelope.
  std::size_t envelope_size() const { return env_.size(); }

 private:
  void constrain(int dof);
  int n_ = 0;
  std::vector<int> perm_;       // new index of each DOF
  std::vector<int> first_;      // first column of each (new) row's envelope
  std::vector<int> row_start_;  // offset of row i's entries (columns first_[i] … i − 1) in env_
  std::vector<double> env_, d_, inv_d_;
  // Scatter of the pattern's lower-triangle entries (original row ≥ column):
  // entry p of the value array goes to env_[dst_[p]] (dst ≥ 0) or to the
  // pivot d_[−dst − 1].
  std::vector<int> src_pos_, dst_;
  std::vector<int> touch_begin_, touch_;  // per DOF: its row's and column's env_ positions
};

}  // namespace piezo::model
