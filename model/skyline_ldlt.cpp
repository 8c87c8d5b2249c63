#include "model/skyline_ldlt.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>
#include <stdexcept>

#include "numerics/simd_clones.hpp"

namespace piezo::model {

namespace {

// Reverse Cuthill–McKee over the DOFs not in `last`, from the start whose
// ordering has the smallest envelope (tried: the DOFs of least degree — a
// mesh's corners — at most kMaxStarts of them), then the `last` DOFs.
// Returns the old index at each new one.
constexpr int kMaxStarts = 16;
std::vector<int> rcm_order(const Eigen::SparseMatrix<double>& p, const std::vector<char>& last) {
  const int n = static_cast<int>(p.rows());
  const int* outer = p.outerIndexPtr();
  const int* inner = p.innerIndexPtr();
  std::vector<int> deg(static_cast<std::size_t>(n));
  for (int j = 0; j < n; ++j) deg[static_cast<std::size_t>(j)] = outer[j + 1] - outer[j];
  auto envelope = [&](const std::vector<int>& order) {
    std::vector<int> pos(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i)
      pos[static_cast<std::size_t>(order[static_cast<std::size_t>(i)])] = i;
    long long env = 0;
    for (int j = 0; j < n; ++j) {
      int lo = pos[static_cast<std::size_t>(j)];
      for (int q = outer[j]; q < outer[j + 1]; ++q)
        lo = std::min(lo, pos[static_cast<std::size_t>(inner[q])]);
      env += pos[static_cast<std::size_t>(j)] - lo;
    }
    return env;
  };
  std::vector<int> best;
  long long best_env = std::numeric_limits<long long>::max();
  std::vector<char> seen;
  std::vector<int> order, nb;
  order.reserve(static_cast<std::size_t>(n));
  std::vector<int> starts;
  for (int i = 0; i < n; ++i)
    if (!last[static_cast<std::size_t>(i)]) starts.push_back(i);
  std::stable_sort(starts.begin(), starts.end(), [&](int a, int b) {
    return deg[static_cast<std::size_t>(a)] < deg[static_cast<std::size_t>(b)];
  });
  if (starts.size() > static_cast<std::size_t>(kMaxStarts))
    starts.resize(static_cast<std::size_t>(kMaxStarts));
  for (int start : starts) {
    seen = last;  // the last DOFs are not walked
    order.clear();
    // Every component from its own lowest-degree DOF after the first.
    int s = start;
    while (true) {
      std::queue<int> q;
      q.push(s);
      seen[static_cast<std::size_t>(s)] = 1;
      while (!q.empty()) {
        const int v = q.front();
        q.pop();
        order.push_back(v);
        nb.clear();
        for (int k = outer[v]; k < outer[v + 1]; ++k)
          if (const int u = inner[k]; !seen[static_cast<std::size_t>(u)]) {
            seen[static_cast<std::size_t>(u)] = 1;
            nb.push_back(u);
          }
        std::stable_sort(nb.begin(), nb.end(), [&](int a, int b) {
          return deg[static_cast<std::size_t>(a)] < deg[static_cast<std::size_t>(b)];
        });
        for (int u : nb) q.push(u);
      }
      s = -1;
      for (int i = 0; i < n; ++i)
        if (!seen[static_cast<std::size_t>(i)] &&
            (s < 0 || deg[static_cast<std::size_t>(i)] < deg[static_cast<std::size_t>(s)]))
          s = i;
      if (s < 0) break;
    }
    std::reverse(order.begin(), order.end());
    for (int i = 0; i < n; ++i)
      if (last[static_cast<std::size_t>(i)]) order.push_back(i);
    const long long env = envelope(order);
    if (env < best_env) {
      best_env = env;
      best = order;
    }
  }
  if (best.empty())  // every DOF "last": natural order
    for (int i = 0; i < n; ++i) best.push_back(i);
  return best;
}

// Lᵀ x = y in place, column by column of Lᵀ (row i of L): AXPYs, element-
// wise, in SIMD clones (numerics/simd_clones.hpp; the forward pass is a dot
// product per row, a sum whose order stays).
PIEZO_SIMD_CLONES void backward(const double* __restrict env, const int* __restrict first,
                                const int* __restrict row_start, double* __restrict y, int n) {
  for (int i = n - 1; i >= 0; --i) {
    const int fi = first[i];
    const double* li = env + row_start[i] - fi;
    const double yi = y[i];
    for (int k = fi; k < i; ++k) y[k] -= li[k] * yi;
  }
}

}  // namespace

void SkylineLdlt::analyse(const SpMat& pattern) {
  if (pattern.rows() != pattern.cols() || !pattern.isCompressed())
    throw std::invalid_argument("SkylineLdlt::analyse: needs a square compressed pattern");
  const int n = static_cast<int>(pattern.rows());
  const int* outer = pattern.outerIndexPtr();
  const int* inner = pattern.innerIndexPtr();
  std::vector<char> last(static_cast<std::size_t>(n), 0);
  for (int j = 0; j < n; ++j) last[static_cast<std::size_t>(j)] = (outer[j + 1] - outer[j]) * 4 > n;
  const std::vector<int> order = rcm_order(pattern, last);
  perm_.assign(static_cast<std::size_t>(n), 0);
  for (int i = 0; i < n; ++i)
    perm_[static_cast<std::size_t>(order[static_cast<std::size_t>(i)])] = i;
  // Envelope: each new row's first column.
  first_.assign(static_cast<std::size_t>(n), 0);
  for (int i = 0; i < n; ++i) first_[static_cast<std::size_t>(i)] = i;
  bool diagonal_everywhere = true;
  for (int j = 0; j < n; ++j) {
    bool diag = false;
    for (int q = outer[j]; q < outer[j + 1]; ++q) {
      const int r = perm_[static_cast<std::size_t>(inner[q])],
                c = perm_[static_cast<std::size_t>(j)];
      if (r == c) diag = true;
      const int hi = std::max(r, c), lo = std::min(r, c);
      first_[static_cast<std::size_t>(hi)] = std::min(first_[static_cast<std::size_t>(hi)], lo);
    }
    diagonal_everywhere = diagonal_everywhere && diag;
  }
  if (!diagonal_everywhere)
    throw std::invalid_argument("SkylineLdlt::analyse: a DOF has no diagonal entry");
  row_start_.assign(static_cast<std::size_t>(n) + 1, 0);
  for (int i = 0; i < n; ++i)
    row_start_[static_cast<std::size_t>(i) + 1] =
        row_start_[static_cast<std::size_t>(i)] + (i - first_[static_cast<std::size_t>(i)]);
  env_.assign(static_cast<std::size_t>(row_start_.back()), 0.0);
  d_.assign(static_cast<std::size_t>(n), 0.0);
  inv_d_.assign(static_cast<std::size_t>(n), 0.0);
  // The scatter of the lower triangle (in the new order) and each DOF's entries.
  src_pos_.clear();
  dst_.clear();
  std::vector<std::vector<int>> touch(static_cast<std::size_t>(n));
  for (int j = 0; j < n; ++j)
    for (int q = outer[j]; q < outer[j + 1]; ++q) {
      const int r = perm_[static_cast<std::size_t>(inner[q])],
                c = perm_[static_cast<std::size_t>(j)];
      if (r < c) continue;  // the upper triangle mirrors it
      src_pos_.push_back(q);
      if (r == c) {
        dst_.push_back(-r - 1);
      } else {
        const int at =
            row_start_[static_cast<std::size_t>(r)] + (c - first_[static_cast<std::size_t>(r)]);
        dst_.push_back(at);
        touch[static_cast<std::size_t>(inner[q])].push_back(at);
        touch[static_cast<std::size_t>(j)].push_back(at);
      }
    }
  touch_begin_.assign(static_cast<std::size_t>(n) + 1, 0);
  touch_.clear();
  for (int d = 0; d < n; ++d) {
    touch_.insert(touch_.end(), touch[static_cast<std::size_t>(d)].begin(),
                  touch[static_cast<std::size_t>(d)].end());
    touch_begin_[static_cast<std::size_t>(d) + 1] = static_cast<int>(touch_.size());
  }
  n_ = n;
}

void SkylineLdlt::constrain(int dof) {
  if (dof < 0 || dof >= n_)
    throw std::invalid_argument("SkylineLdlt: constrained DOF out of range");
  const auto d = static_cast<std::size_t>(dof);
  for (int t = touch_begin_[d]; t < touch_begin_[d + 1]; ++t)
    env_[static_cast<std::size_t>(touch_[static_cast<std::size_t>(t)])] = 0.0;
  d_[static_cast<std::size_t>(perm_[d])] = 1.0;
}

bool SkylineLdlt::factorize(const double* values, std::span<const int> clamped, int extra_clamped) {
  if (!analysed()) throw std::logic_error("SkylineLdlt::factorize before analyse");
  std::fill(env_.begin(), env_.end(), 0.0);  // the fill inside the envelope
  for (std::size_t k = 0; k < src_pos_.size(); ++k) {
    const int t = dst_[k];
    const double v = values[src_pos_[k]];
    if (t >= 0)
      env_[static_cast<std::size_t>(t)] = v;
    else
      d_[static_cast<std::size_t>(-t - 1)] = v;
  }
  if (extra_clamped >= 0) constrain(extra_clamped);
  for (int c : clamped) constrain(c);
  // Row-oriented Crout LDLᵀ: row i's entries first become u_ij = L_ij·D_j
  // (against the finished rows j < i), then L_ij = u_ij / D_j and
  // D_i = A_ii − Σ_j u_ij·L_ij.
  double* env = env_.data();
  for (int i = 0; i < n_; ++i) {
    const int fi = first_[static_cast<std::size_t>(i)];
    double* li =
        env + row_start_[static_cast<std::size_t>(i)] - fi;  // li[k] = row i's entry at column k
    for (int j = fi; j < i; ++j) {
      const int fj = first_[static_cast<std::size_t>(j)];
      const double* lj = env + row_start_[static_cast<std::size_t>(j)] - fj;
      double s = li[j];
      for (int k = std::max(fi, fj); k < j; ++k) s -= li[k] * lj[k];
      li[j] = s;
    }
    double di = d_[static_cast<std::size_t>(i)];
    for (int j = fi; j < i; ++j) {
      const double u = li[j];
      const double l = u / d_[static_cast<std::size_t>(j)];
      di -= u * l;
      li[j] = l;
    }
    if (!(di != 0.0) || !std::isfinite(di)) return false;
    d_[static_cast<std::size_t>(i)] = di;
    inv_d_[static_cast<std::size_t>(i)] = 1.0 / di;
  }
  return true;
}

void SkylineLdlt::solve(const double* b, double* x) const {
  thread_local std::vector<double> work;
  work.resize(static_cast<std::size_t>(n_));
  double* y = work.data();
  for (int i = 0; i < n_; ++i) y[perm_[static_cast<std::size_t>(i)]] = b[i];
  const double* env = env_.data();
  for (int i = 0; i < n_; ++i) {  // L y = P b
    const int fi = first_[static_cast<std::size_t>(i)];
    const double* li = env + row_start_[static_cast<std::size_t>(i)] - fi;
    double s = y[i];
    for (int k = fi; k < i; ++k) s -= li[k] * y[k];
    y[i] = s;
  }
  for (int i = 0; i < n_; ++i) y[i] *= inv_d_[static_cast<std::size_t>(i)];
  backward(env, first_.data(), row_start_.data(), y, n_);  // Lᵀ x = D⁻¹ y
  for (int i = 0; i < n_; ++i) x[i] = y[perm_[static_cast<std::size_t>(i)]];
}

}  // namespace piezo::model
