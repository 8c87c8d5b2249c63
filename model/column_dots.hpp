#pragma once
// y_j = Σ_p a_pj·x_(row p), one dot product per column of a column-major
// sparse matrix (= Aᵀx): the Lanczos operator's two products with the mass
// matrix's Cholesky factor (modal.cpp, issue 43). The columns are taken four
// at a time, each its own running sum in its stored order — so the result is
// bit for bit that of one scalar loop per column — and the four sums run in
// the four lanes of an AVX2 register where the CPU has one (the columns
// sorted by length so that four neighbours share most of their length; the
// entries of their shared part interleaved, four values and four row
// indices side by side; each column's rest after it, as stored). Without
// AVX2 the same order in scalar code.
#include <vector>

#include "model/assembler.hpp"

namespace piezo::model {

class ColumnDots {
 public:
  ColumnDots() = default;
  explicit ColumnDots(const SpMat& a);
  // y[j] for every column j of a (x: a.rows() values, y: a.cols()).
  void apply(const double* x, double* y) const;
  Eigen::Index cols() const { return n_; }

 private:
  struct Group {
    int col[4];      // the output indices (columns of a)
    int shared;      // the entries every column of the group has (from its start)
    int offset;      // into vals_/rows_ (4·shared interleaved entries)
    int rest[4][2];  // each column's remaining entries: [begin, end) in a's arrays
  };
  Eigen::Index n_ = 0;
  std::vector<Group> groups_;
  std::vector<int> single_;  // columns beyond the last full group (scalar)
  std::vector<double> vals_;
  std::vector<int> rows_;
  std::vector<int> outer_, inner_;  // a's own arrays (the rests and the singles)
  std::vector<double> values_;
  void finish(const Group& g, double* s, const double* x, double* y) const;  // a group's rests, y
  void singles(const double* x, double* y) const;                             // the columns beyond the groups
  void apply_scalar(const double* x, double* y) const;
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && !defined(PIEZO_NO_SIMD_CLONES)
  __attribute__((target("avx2"))) void apply_avx2(const double* x, double* y) const;
#endif
};

}  // namespace piezo::model
