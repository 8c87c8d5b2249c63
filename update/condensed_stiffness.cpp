#include "update/condensed_stiffness.hpp"

#include <stdexcept>

namespace piezo::update {

using model::SpMat;

CondensedStiffness::CondensedStiffness(const model::TubeModel& tube,
                                       const model::PiezoMaterialE& material,
                                       model::Electrodes electrodes)
    : tube_(&tube) {
  model::validate(material, "CondensedStiffness");
  const int np = tube.n_phi();
  n_c_ = electrodes == model::Electrodes::open_circuit ? np : np - 1;  // electrode is last
  const auto w = model::weights(material);
  kuu_ = k_uu(w);
  b_ = k_phi_u(w);
  SpMat na = -k_phi_phi(w);
  neg_a_.compute(na);
  if (neg_a_.info() != Eigen::Success)
    throw std::runtime_error("CondensedStiffness: K_ΦΦ block is singular");
}

SpMat CondensedStiffness::k_uu(const model::MaterialWeights& w) const {
  const auto& s = tube_->split();
  SpMat k = w[0] * s.k_c[0];
  for (int i = 1; i < 5; ++i) k += w[i] * s.k_c[i];
  return k;
}

SpMat CondensedStiffness::k_phi_u(const model::MaterialWeights& w) const {
  const auto& s = tube_->split();
  SpMat kup = w[5] * s.k_e[0];
  for (int i = 1; i < 3; ++i) kup += w[5 + i] * s.k_e[i];
  SpMat kpu = SpMat(kup.transpose()).topRows(n_c_);
  return kpu;
}

SpMat CondensedStiffness::k_phi_phi(const model::MaterialWeights& w) const {
  const auto& s = tube_->split();
  SpMat a = w[8] * s.k_eps[0] + w[9] * s.k_eps[1];
  return SpMat(a.topLeftCorner(n_c_, n_c_));
}

Eigen::MatrixXd CondensedStiffness::bilinear(const Eigen::MatrixXd& x,
                                             const Eigen::MatrixXd& y) const {
  // K = K_UU − Bᵀ A⁻¹ B = K_UU + Bᵀ N⁻¹ B with N = −A.
  const Eigen::MatrixXd bx = b_ * x, by = b_ * y;
  const Eigen::MatrixXd py = neg_a_.solve(by);
  return x.transpose() * (kuu_ * y) + bx.transpose() * py;
}

Eigen::MatrixXd CondensedStiffness::dbilinear(const model::MaterialWeights& dw,
                                              const Eigen::MatrixXd& x,
                                              const Eigen::MatrixXd& y) const {
  // d(Bᵀ N⁻¹ B) = dBᵀ N⁻¹ B + Bᵀ N⁻¹ dB − Bᵀ N⁻¹ dN N⁻¹ B, dN = −dA:
  // Xᵀ dK Y = Xᵀ dK_UU Y + (dB X)ᵀ Ψ_Y + Ψ_Xᵀ (dB Y) + Ψ_Xᵀ dA Ψ_Y, Ψ = N⁻¹ B (·).
  const SpMat dkuu = k_uu(dw), db = k_phi_u(dw), da = k_phi_phi(dw);
  const Eigen::MatrixXd psx = neg_a_.solve(Eigen::MatrixXd(b_ * x));
  const Eigen::MatrixXd psy = neg_a_.solve(Eigen::MatrixXd(b_ * y));
  return x.transpose() * (dkuu * y) + (db * x).transpose() * psy + psx.transpose() * (db * y) +
         psx.transpose() * (da * psy);
}

}  // namespace piezo::update
