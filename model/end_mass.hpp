#pragma once
// Mass loading of the tube's end faces (effect `mass_loading`, model/effects.hpp):
// glue, electrode leads or a mounting ring modelled as a thin layer bonded to
// both end faces, rigid through its thickness, so it moves with the face in u_r
// and u_z and adds only kinetic energy. Half of the added mass sits on each end
// face, spread over the annulus ri ≤ r ≤ ro in proportion to area, i.e. with
// the constant areal density μ = (f·m_tube/2) / (π(ro² − ri²)) for an added
// fraction f of the tube mass m_tube = ρπ(ro² − ri²)L.
//
// Its mass matrix is the consistent line-mass integral over the end edges of
// the axisymmetric mesh (the same ∫N_uᵀN_u dV form as seed eq. 73 restricted
// to the faces z = ±L/2, with dA = 2πr dr):
//     ΔM_ab = μ ∫ N_a(r) N_b(r) 2πr dr   on u_r–u_r and on u_z–u_z,
// with the quadratic edge functions of the 9-node element, integrated exactly
// (3-point Gauss: N_a N_b r has degree 5 on a straight edge). ΔM is built ONCE
// per mesh for f = 1 and scaled by f: M(f) = M + f·ΔM (model/tube_model.hpp).
#include <Eigen/SparseCore>
#include <vector>

#include "model/mesh.hpp"
#include "model/tube_geometry.hpp"

namespace piezo::model {

// ρ·π(ro² − ri²)·L (kg): the mass of the bare tube.
double tube_mass_kg(const TubeGeometry& g);

// ΔM for an added mass equal to the tube mass (f = 1), as triplets on the
// global U DOFs (u_r, u_z of the end-face nodes; duplicates are summed).
std::vector<Eigen::Triplet<double>> end_face_mass_triplets(const TubeMesh& mesh, const DofMap& dofs,
                                                           const TubeGeometry& g);

}  // namespace piezo::model
