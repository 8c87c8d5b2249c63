#pragma once
// Assembler: element split matrices → one sparse system (seed eqs 77-84).
// All parameter matrices share ONE symmetric sparsity pattern over the full
// DOF vector x = [U; Φ_int; V] (model/mesh.hpp), so that re-weighting for a
// new material (eqs 234, 242, 245) is an AXPY over value arrays, and a sparse
// factorisation analysed once can be reused for every material.
#include <Eigen/SparseCore>
#include <array>
#include <complex>
#include <span>
#include <vector>

#include "model/material.hpp"
#include "model/mesh.hpp"

namespace piezo::model {

using SpMat = Eigen::SparseMatrix<double>;
using SpMatC = Eigen::SparseMatrix<std::complex<double>>;

class SplitSystem {
 public:
  SplitSystem() = default;
  SplitSystem(const TubeMesh& mesh, const DofMap& dofs, double density_kg_m3, int gauss_points);

  int size() const { return static_cast<int>(pattern_.rows()); }
  // Pattern (both triangles stored); its values are the unweighted sum and carry no meaning.
  const SpMat& pattern() const { return pattern_; }
  const Eigen::VectorXd& values(MaterialParam p) const { return k_[static_cast<int>(p)]; }
  const Eigen::VectorXd& mass_values() const { return m_; }

  // The end-face mass ΔM for an added fraction f = 1 of the tube mass
  // (model/end_mass.hpp), scattered onto the shared pattern (it couples only
  // DOFs of one element edge, so it fits). Throws std::invalid_argument for an
  // entry outside the pattern.
  void set_end_mass(std::span<const Eigen::Triplet<double>> unit_end_mass);
  const Eigen::VectorXd& end_mass_values() const { return m_end_; }

  // out ← Σ_p w_p·K_p − σ·(M + f·ΔM) on the shared pattern (out is given the
  // pattern if needed); f = end_mass_fraction (needs set_end_mass when ≠ 0).
  void combine(const MaterialWeights& w, double sigma, SpMat& out,
               double end_mass_fraction = 0.0) const;
  // Same with complex weights and complex mass factor (for the direct harmonic solve):
  // out ← Σ_p w_p·K_p + w_m·(M + f·ΔM).
  void combine(const std::array<std::complex<double>, kNumMaterialParams>& w,
               std::complex<double> w_m, SpMatC& out, double end_mass_fraction = 0.0) const;
  // One split matrix (or the mass, or ΔM) as a standalone sparse matrix on the full DOFs.
  SpMat matrix(MaterialParam p) const;
  SpMat mass() const;
  SpMat end_mass() const;
  // Position of (row, col) in the value arrays; −1 if not in the pattern.
  int position(int row, int col) const;
  // Position of the mirror (col, row) of the entry at position p (the pattern is
  // symmetric): no search (constraining a DOF touches its whole row and column).
  int transposed(int p) const { return transpose_[static_cast<std::size_t>(p)]; }

 private:
  SpMat with_values(const Eigen::VectorXd& v) const;
  // M + f·ΔM on the pattern's values.
  Eigen::VectorXd loaded_mass(double end_mass_fraction, const char* fn) const;
  SpMat pattern_;
  std::array<Eigen::VectorXd, kNumMaterialParams> k_;
  Eigen::VectorXd m_, m_end_;
  std::vector<int> transpose_;  // transposed(p)
};

}  // namespace piezo::model
