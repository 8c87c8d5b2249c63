#pragma once
// The electro-elastic stiffness seen by the displacements after the potentials
// are condensed (seed eqs 92, 206-209, 247-250), as bilinear forms XᵀKY and
// their derivatives with respect to the ten e-form weights. Built on the split
// matrices of model::TubeModel (eqs 234, 242, 245), so any material, any
// combination of weights (the CMCM sub-matrices K_n of eqs 239-240, 244) and
// either electrode condition is one object:
//   short circuit: outer electrode grounded, internal potentials condensed;
//   open circuit:  internal potentials and the electrode (zero net charge) condensed.
//   K = K_UU − K_UΦ K_ΦΦ⁻¹ K_ΦU  over the condensed potentials.
// Nothing here is assembled twice: only the small K_ΦΦ block is factorised.
#include <Eigen/Core>
#include <Eigen/SparseCholesky>

#include "model/coupled_solver.hpp"
#include "model/tube_model.hpp"

namespace piezo::update {

class CondensedStiffness {
 public:
  CondensedStiffness(const model::TubeModel& tube, const model::PiezoMaterialE& material,
                     model::Electrodes electrodes);

  // Xᵀ K Y for U-space columns X (n_u × p), Y (n_u × q).
  Eigen::MatrixXd bilinear(const Eigen::MatrixXd& x, const Eigen::MatrixXd& y) const;
  // Xᵀ (Σ_p dw_p ∂K/∂w_p) Y, the directional derivative at this material.
  Eigen::MatrixXd dbilinear(const model::MaterialWeights& dw, const Eigen::MatrixXd& x,
                            const Eigen::MatrixXd& y) const;

 private:
  model::SpMat k_phi_u(const model::MaterialWeights& w) const;  // condensed rows of K_ΦU
  model::SpMat k_phi_phi(const model::MaterialWeights& w) const;
  model::SpMat k_uu(const model::MaterialWeights& w) const;

  const model::TubeModel* tube_;
  int n_c_ = 0;  // condensed potential DOFs
  model::SpMat kuu_, b_;
  Eigen::SimplicialLDLT<model::SpMat> neg_a_;  // factor of −K_ΦΦ (positive definite)
};

// Directional derivatives of the e-form weights with respect to one scalar
// coordinate, by central differences (relative step h): the weights are smooth
// (rational) functions of the updating coordinates.
template <class F>
model::MaterialWeights weight_tangent(const F& material_of, double x, double h = 1e-6) {
  const double dx = h * (x != 0 ? std::abs(x) : 1.0);
  const auto wp = model::weights(material_of(x + dx));
  const auto wm = model::weights(material_of(x - dx));
  model::MaterialWeights d{};
  for (int p = 0; p < model::kNumMaterialParams; ++p) d[p] = (wp[p] - wm[p]) / (2.0 * dx);
  return d;
}

}  // namespace piezo::update
