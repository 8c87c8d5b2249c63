#include "model/assembler.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "model/element.hpp"
#include "numerics/simd_clones.hpp"

namespace piezo::model {

namespace {

std::array<int, kElemDofs> element_dofs(const TubeMesh& mesh, const DofMap& dofs, int e) {
  std::array<int, kElemDofs> g{};
  const auto& en = mesh.element(e);
  for (int a = 0; a < kElemNodes; ++a) {
    g[2 * a] = dofs.u_r(en[a]);
    g[2 * a + 1] = dofs.u_z(en[a]);
    g[18 + a] = dofs.phi(en[a]);  // −1: grounded inner surface
  }
  return g;
}

}  // namespace

SplitSystem::SplitSystem(const TubeMesh& mesh, const DofMap& dofs, double density_kg_m3,
                         int gauss_points) {
  if (!(density_kg_m3 > 0)) throw std::invalid_argument("SplitSystem: density must be > 0");
  const int n = dofs.n_total();
  // 1. Pattern: every pair of DOFs sharing an element.
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(static_cast<std::size_t>(mesh.num_elements()) * kElemDofs * kElemDofs);
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const auto g = element_dofs(mesh, dofs, e);
    for (int b : g)
      for (int a : g)
        if (a >= 0 && b >= 0) trip.emplace_back(a, b, 1.0);
  }
  pattern_.resize(n, n);
  pattern_.setFromTriplets(trip.begin(), trip.end());
  pattern_.makeCompressed();
  const auto nnz = pattern_.nonZeros();
  // 1b. Where each entry's mirror (col, row) sits: the pattern is symmetric, and
  // walking the columns in order meets the entries of column i in row order.
  {
    const int* outer = pattern_.outerIndexPtr();
    const int* inner = pattern_.innerIndexPtr();
    std::vector<int> cursor(outer, outer + n);
    transpose_.resize(static_cast<std::size_t>(nnz));
    for (int j = 0; j < n; ++j)
      for (int p = outer[j]; p < outer[j + 1]; ++p) {
        const int q = cursor[static_cast<std::size_t>(inner[p])]++;
        if (q >= outer[inner[p] + 1] || inner[q] != j)
          throw std::logic_error("SplitSystem: the element pattern is not symmetric");
        transpose_[static_cast<std::size_t>(p)] = q;
      }
  }
  for (auto& v : k_) v.setZero(nnz);
  m_.setZero(nnz);

  // 2. Scatter the element split matrices into the value arrays (eqs 80-84).
  ElementSplit es;
  std::array<Node, kElemNodes> x;
  std::array<int, kElemDofs * kElemDofs> pos{};
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const auto g = element_dofs(mesh, dofs, e);
    for (int a = 0; a < kElemNodes; ++a) x[a] = mesh.nodes()[mesh.element(e)[a]];
    element_split(x, gauss_points, es);
    for (int b = 0; b < kElemDofs; ++b)
      for (int a = 0; a < kElemDofs; ++a)
        pos[b * kElemDofs + a] = (g[a] >= 0 && g[b] >= 0) ? position(g[a], g[b]) : -1;
    for (int b = 0; b < kElemDofs; ++b)
      for (int a = 0; a < kElemDofs; ++a) {
        const int p = pos[b * kElemDofs + a];
        if (p < 0) continue;
        for (int q = 0; q < kNumMaterialParams; ++q) k_[q][p] += es.k[q](a, b);
        m_[p] += density_kg_m3 * es.m(a, b);
      }
  }
}

int SplitSystem::position(int row, int col) const {
  if (row < 0 || col < 0 || row >= pattern_.rows() || col >= pattern_.cols()) return -1;
  const int* inner = pattern_.innerIndexPtr();
  const int* begin = inner + pattern_.outerIndexPtr()[col];
  const int* end = inner + pattern_.outerIndexPtr()[col + 1];
  const int* it = std::lower_bound(begin, end, row);
  return (it != end && *it == row) ? static_cast<int>(it - inner) : -1;
}

void SplitSystem::set_end_mass(std::span<const Eigen::Triplet<double>> unit_end_mass) {
  m_end_.setZero(pattern_.nonZeros());
  for (const auto& t : unit_end_mass) {
    const int p = position(t.row(), t.col());
    if (p < 0) throw std::invalid_argument("SplitSystem::set_end_mass: entry outside the pattern");
    m_end_[p] += t.value();
  }
}

Eigen::VectorXd SplitSystem::loaded_mass(double f, const char* fn) const {
  if (f == 0.0) return m_;
  if (!std::isfinite(f) || f < 0.0)
    throw std::invalid_argument(std::string(fn) + ": end_mass_fraction must be finite and >= 0");
  if (m_end_.size() != m_.size())
    throw std::invalid_argument(std::string(fn) + ": no end-face mass set (set_end_mass)");
  return m_ + f * m_end_;
}

namespace {
// v = −σ·(m + f·m_end) + Σ_q w_q·k_q over the pattern's values, pass by pass
// in q's order (each element's operations those of the Eigen expressions
// this replaced, so the same bits), in SIMD clones (numerics/simd_clones.hpp).
// The passes run block by block (kBlock values: v's block stays in the L1
// cache through its eleven passes instead of streaming v from L2 eleven
// times); each value's operations and their order are unchanged.
PIEZO_SIMD_CLONES void weighted_values(double* __restrict v, std::size_t n, double sigma, const double* __restrict m,
                                       const double* __restrict m_end, double f,
                                       const std::array<const double*, kNumMaterialParams>& k, const MaterialWeights& w) {
  constexpr std::size_t kBlock = 512;
  for (std::size_t b0 = 0; b0 < n; b0 += kBlock) {
    const std::size_t b1 = std::min(n, b0 + kBlock);
    if (m_end)
      for (std::size_t i = b0; i < b1; ++i) v[i] = -sigma * (m[i] + f * m_end[i]);
    else
      for (std::size_t i = b0; i < b1; ++i) v[i] = -sigma * m[i];
    for (int q = 0; q < kNumMaterialParams; ++q) {
      const double wq = w[static_cast<std::size_t>(q)];
      if (wq == 0.0) continue;
      const double* __restrict kq = k[static_cast<std::size_t>(q)];
      for (std::size_t i = b0; i < b1; ++i) v[i] += wq * kq[i];
    }
  }
}
}  // namespace

void SplitSystem::combine(const MaterialWeights& w, double sigma, SpMat& out,
                          double end_mass_fraction) const {
  if (out.nonZeros() != pattern_.nonZeros() || out.rows() != pattern_.rows()) out = pattern_;
  if (end_mass_fraction != 0.0) {  // (loaded_mass's checks)
    if (!std::isfinite(end_mass_fraction) || end_mass_fraction < 0.0)
      throw std::invalid_argument("SplitSystem::combine: end_mass_fraction must be finite and >= 0");
    if (m_end_.size() != m_.size()) throw std::invalid_argument("SplitSystem::combine: no end-face mass set (set_end_mass)");
  }
  std::array<const double*, kNumMaterialParams> k{};
  for (int q = 0; q < kNumMaterialParams; ++q) k[static_cast<std::size_t>(q)] = k_[q].data();
  weighted_values(out.valuePtr(), static_cast<std::size_t>(out.nonZeros()), sigma, m_.data(),
                  end_mass_fraction == 0.0 ? nullptr : m_end_.data(), end_mass_fraction, k, w);
}

void SplitSystem::combine(const std::array<std::complex<double>, kNumMaterialParams>& w,
                          std::complex<double> w_m, SpMatC& out, double end_mass_fraction) const {
  if (out.nonZeros() != pattern_.nonZeros() || out.rows() != pattern_.rows())
    out = pattern_.cast<std::complex<double>>();
  Eigen::Map<Eigen::VectorXcd> v(out.valuePtr(), out.nonZeros());
  if (end_mass_fraction == 0.0)
    v = w_m * m_.cast<std::complex<double>>();
  else
    v = w_m * loaded_mass(end_mass_fraction, "SplitSystem::combine").cast<std::complex<double>>();
  for (int q = 0; q < kNumMaterialParams; ++q)
    if (w[q] != 0.0) v += w[q] * k_[q].cast<std::complex<double>>();
}

SpMat SplitSystem::with_values(const Eigen::VectorXd& v) const {
  SpMat s = pattern_;
  Eigen::Map<Eigen::VectorXd>(s.valuePtr(), s.nonZeros()) = v;
  return s;
}

SpMat SplitSystem::matrix(MaterialParam p) const { return with_values(values(p)); }
SpMat SplitSystem::mass() const { return with_values(m_); }
SpMat SplitSystem::end_mass() const {
  return m_end_.size() == m_.size() ? with_values(m_end_)
                                    : with_values(Eigen::VectorXd::Zero(m_.size()));
}

}  // namespace piezo::model
