#include "model/column_dots.hpp"

#include <algorithm>
#include <numeric>
#include <stdexcept>

#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && !defined(PIEZO_NO_SIMD_CLONES)
#include <immintrin.h>
#define PIEZO_COLUMN_DOTS_AVX2 1
#endif

namespace piezo::model {

ColumnDots::ColumnDots(const SpMat& a) : n_(a.cols()) {
  if (!a.isCompressed()) throw std::invalid_argument("ColumnDots: needs a compressed matrix");
  const int* outer = a.outerIndexPtr();
  outer_.assign(outer, outer + a.cols() + 1);
  inner_.assign(a.innerIndexPtr(), a.innerIndexPtr() + a.nonZeros());
  values_.assign(a.valuePtr(), a.valuePtr() + a.nonZeros());
  std::vector<int> order(static_cast<std::size_t>(a.cols()));
  std::iota(order.begin(), order.end(), 0);
  auto length = [&](int j) { return outer[j + 1] - outer[j]; };
  std::stable_sort(order.begin(), order.end(), [&](int p, int q) { return length(p) < length(q); });
  std::size_t k = 0;
  for (; k + 4 <= order.size(); k += 4) {
    Group g{};
    g.shared = length(order[k]);  // (ascending: the group's shortest)
    g.offset = static_cast<int>(vals_.size());
    for (int l = 0; l < 4; ++l) {
      const int j = order[k + static_cast<std::size_t>(l)];
      g.col[l] = j;
      g.rest[l][0] = outer[j] + g.shared;
      g.rest[l][1] = outer[j + 1];
    }
    for (int t = 0; t < g.shared; ++t)
      for (int l = 0; l < 4; ++l) {
        vals_.push_back(values_[static_cast<std::size_t>(outer[g.col[l]] + t)]);
        rows_.push_back(inner_[static_cast<std::size_t>(outer[g.col[l]] + t)]);
      }
    groups_.push_back(g);
  }
  for (; k < order.size(); ++k) single_.push_back(order[k]);
}

void ColumnDots::finish(const Group& g, double* s, const double* x, double* y) const {
  for (int l = 0; l < 4; ++l) {  // each column's rest, in its stored order
    for (int p = g.rest[l][0]; p < g.rest[l][1]; ++p)
      s[l] += values_[static_cast<std::size_t>(p)] * x[inner_[static_cast<std::size_t>(p)]];
    y[g.col[l]] = s[l];
  }
}

void ColumnDots::singles(const double* x, double* y) const {
  for (int j : single_) {
    double s = 0.0;
    for (int p = outer_[static_cast<std::size_t>(j)]; p < outer_[static_cast<std::size_t>(j) + 1]; ++p)
      s += values_[static_cast<std::size_t>(p)] * x[inner_[static_cast<std::size_t>(p)]];
    y[j] = s;
  }
}

void ColumnDots::apply_scalar(const double* x, double* y) const {
  for (const Group& g : groups_) {
    const double* v = vals_.data() + g.offset;
    const int* r = rows_.data() + g.offset;
    double s[4] = {0.0, 0.0, 0.0, 0.0};
    for (int t = 0; t < g.shared; ++t, v += 4, r += 4) {
      s[0] += v[0] * x[r[0]];
      s[1] += v[1] * x[r[1]];
      s[2] += v[2] * x[r[2]];
      s[3] += v[3] * x[r[3]];
    }
    finish(g, s, x, y);
  }
  singles(x, y);
}

#ifdef PIEZO_COLUMN_DOTS_AVX2
// The shared parts four lanes at a time: a multiply, then an add (AVX2 has no
// FMA, so no contraction: each lane's rounding is the scalar loop's).
__attribute__((target("avx2"))) void ColumnDots::apply_avx2(const double* x, double* y) const {
  for (const Group& g : groups_) {
    const double* v = vals_.data() + g.offset;
    const int* r = rows_.data() + g.offset;
    __m256d acc = _mm256_setzero_pd();
    for (int t = 0; t < g.shared; ++t, v += 4, r += 4) {
      const __m256d xv = _mm256_set_pd(x[r[3]], x[r[2]], x[r[1]], x[r[0]]);
      acc = _mm256_add_pd(acc, _mm256_mul_pd(_mm256_loadu_pd(v), xv));
    }
    alignas(32) double s[4];
    _mm256_store_pd(s, acc);
    finish(g, s, x, y);
  }
  singles(x, y);
}
#endif

void ColumnDots::apply(const double* x, double* y) const {
#ifdef PIEZO_COLUMN_DOTS_AVX2
  static const bool avx2 = __builtin_cpu_supports("avx2");
  if (avx2) return apply_avx2(x, y);
#endif
  apply_scalar(x, y);
}

}  // namespace piezo::model
