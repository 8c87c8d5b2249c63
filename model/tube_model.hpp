#pragma once
// The assembled tube: geometry + mesh + DOF map + split system, built ONCE and
// re-weighted for any material without re-assembly (seed §6.4, eqs 234-246).
// This is the object the updating layer keeps for hundreds of evaluations.
//
// Sign convention: as in the seed (eq. 76), K_ΦΦ = −∫ B_φᵀ εS B_φ dV is negative
// semidefinite, so its split matrices K_εk are too. Electrode charge on the
// outer electrode: Q = −(K_ΦU U + K_ΦΦ Φ)_V (eq. 72 with G = −Q on the electrode).
#include <array>
#include <memory>
#include <vector>

#include "model/assembler.hpp"
#include "model/material.hpp"
#include "model/mesh.hpp"
#include "model/tube_geometry.hpp"

namespace piezo::model {

// Split matrices as blocks of the full system (public data for update/).
// Φ = [Φ_int; V]: the last column of k_e / last row+column of k_eps is the
// outer electrode DOF.
struct SplitMatrices {
  SpMat m;                    // M, n_u × n_u (eq. 80), density of the geometry included
  SpMat m_end;                // ΔM of the end-face mass for f = 1 (model/end_mass.hpp), n_u × n_u
  std::array<SpMat, 5> k_c;   // ∂K_UU/∂cE_ij for cE11, cE12, cE13, cE33, cE44 (eq. 234)
  std::array<SpMat, 3> k_e;   // ∂K_UΦ/∂e_k for e31, e33, e15, n_u × n_phi (eq. 242)
  std::array<SpMat, 2> k_eps; // ∂K_ΦΦ/∂εS_k for εS11, εS33, n_phi × n_phi (eq. 245)
};

// Weighted blocks for one material (eqs 79-84).
struct AssembledMatrices {
  SpMat m, k_uu, k_uphi, k_phiphi;
};

// What the mesh covers. A tube symmetric about its mid-plane (geometry,
// poling, electrodes and end-face masses alike) has its electrically active
// modes among the symmetric ones (u_z odd in z): its upper half z ∈ [0, L/2]
// with u_z = 0 on the mid-plane carries them exactly, on half the DOFs.
//   whole       the tube, z ∈ [−L/2, L/2]
//   upper_half  z ∈ [0, L/2]: mesh rows = the whole tube's upper rows (n_axial/2
//               elements of the same size), the bottom face is the mid-plane
//               (symmetry_plane_dofs(): its u_z, to be constrained by the
//               solver), and the end-face mass sits on the top face only
//               with the whole tube's areal density. geometry() is the
//               half's (length L/2).
enum class TubeExtent { whole, upper_half };

class TubeModel {
 public:
  explicit TubeModel(const TubeGeometry& geometry, const MeshOptions& mesh = {},
                     int gauss_points = 3, TubeExtent extent = TubeExtent::whole);

  // The upper half of this (whole) tube, or nullptr when its mesh has an odd
  // number of axial elements (no node row on the mid-plane).
  std::unique_ptr<TubeModel> upper_half() const;
  TubeExtent extent() const { return extent_; }
  // u_z DOFs of the mid-plane (upper_half), empty for the whole tube.
  const std::vector<int>& symmetry_plane_dofs() const { return symmetry_plane_; }

  const TubeGeometry& geometry() const { return geometry_; }
  const TubeMesh& mesh() const { return *mesh_; }
  const DofMap& dofs() const { return *dofs_; }
  const SplitSystem& system() const { return system_; }
  const SplitMatrices& split() const { return split_; }
  int n_u() const { return dofs_->n_u(); }
  int n_phi() const { return dofs_->n_phi(); }

  // M(f) = M + f·ΔM: the mass matrix with an added end-face mass of f times the
  // tube mass (effect `mass_loading`); f = 0 is the bare tube. No re-assembly.
  SpMat mass(double end_mass_fraction = 0.0) const;
  double tube_mass() const;  // ρπ(ro² − ri²)L, kg

  // K_UU = Σ c_ij K_cij, K_UΦ = Σ e_k K_ek, K_ΦΦ = Σ ε_k K_εk (eqs 234, 242, 245).
  AssembledMatrices assemble(const PiezoMaterialE& material) const;

  // Mid-plane mirror of a U vector: (P u)_r(n) = u_r(mirror n), (P u)_z(n) = −u_z(mirror n).
  Eigen::VectorXd mirror(const Eigen::VectorXd& u) const;

  // Capacitance of the radially poled tube, eq. 200: 2π ε33 L / ln(Do/Di).
  double analytic_capacitance(double eps33) const;

 private:
  TubeGeometry geometry_;
  int gauss_points_ = 3;
  TubeExtent extent_ = TubeExtent::whole;
  std::vector<int> symmetry_plane_;
  std::unique_ptr<TubeMesh> mesh_;
  std::unique_ptr<DofMap> dofs_;
  SplitSystem system_;
  SplitMatrices split_;
};

}  // namespace piezo::model
