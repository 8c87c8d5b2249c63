#pragma once
// Acoustic load on the tube's OUTER cylindrical surface as a radial dashpot
// (plane-wave radiation impedance, an out-of-catalogue effect of issue 21: the
// simulated bench may apply it, the gap diagnosis never fits it). A fluid of
// characteristic impedance Z_a = ρ_f·c_f (Pa·s/m; water ≈ 1.48e6) in contact
// with r = r_o exerts the traction t_r = −Z_a·u̇_r, whose virtual work over the
// surface gives the damping matrix (the same ∫NᵀN form as seed eq. 73, on the
// surface instead of the volume; axisymmetric, dA = 2π r_o dz):
//     C_a,ab = Z_a ∫_outer N_a(z) N_b(z) 2π r_o dz      on u_r–u_r only,
// with the quadratic edge functions of the 9-node element, integrated exactly
// (3-point Gauss: N_a N_b has degree 4 on a straight edge). Projected on a
// mass-normalised mode φ_k it adds c_k += φ_kᵀ C_a φ_k (1/s) to the modal
// damping of x_k'' + c_k x_k' + ω_k² x_k = p_k v (model/port_model.hpp),
// neglecting the coupling between modes through C_a (its off-diagonal terms,
// small when c_k ≪ |ω_k − ω_j|). Z_a = ρc is the plane-wave limit (k·r_o ≫ 1);
// a real cylinder radiates less at low k·r_o: this is a test input, not a
// radiation model.
#include <Eigen/SparseCore>
#include <vector>

#include "model/mesh.hpp"

namespace piezo::model {

// C_a for Z_a = 1 Pa·s/m as triplets on the global u_r DOFs of the outer
// surface nodes (duplicates summed). Scale by Z_a.
std::vector<Eigen::Triplet<double>> outer_surface_damping_triplets(const TubeMesh& mesh,
                                                                   const DofMap& dofs);

// φᵀ C_a φ for Z_a = 1 (the per-mode damping per unit impedance, m²/kg for an
// M-normalised φ), without assembling C_a: one edge integral per outer edge.
double outer_surface_modal_damping(const TubeMesh& mesh, const DofMap& dofs,
                                   const Eigen::VectorXd& phi);

}  // namespace piezo::model
