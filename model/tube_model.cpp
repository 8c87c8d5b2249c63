#include "model/tube_model.hpp"

#include <cmath>
#include <stdexcept>

#include "model/end_mass.hpp"

namespace piezo::model {

TubeModel::TubeModel(const TubeGeometry& geometry, const MeshOptions& mesh, int gauss_points,
                     TubeExtent extent)
    : geometry_(geometry), gauss_points_(gauss_points), extent_(extent) {
  geometry_.validate();
  mesh_ = std::make_unique<TubeMesh>(geometry_, mesh);
  dofs_ = std::make_unique<DofMap>(*mesh_);
  system_ = SplitSystem(*mesh_, *dofs_, geometry_.density_kg_m3, gauss_points);
  auto end_mass = end_face_mass_triplets(*mesh_, *dofs_, geometry_);
  if (extent_ == TubeExtent::upper_half) {
    // The whole tube's top-face mass: its areal density ρL/2 per unit f is twice
    // the half's own ρ(L/2)/2, and the mid-plane (bottom face) carries none.
    const int top = mesh_->nodes_z() - 1;
    std::vector<Eigen::Triplet<double>> kept;
    for (const auto& t : end_mass)
      if ((t.row() / 2) / mesh_->nodes_r() == top) kept.emplace_back(t.row(), t.col(), 2.0 * t.value());
    end_mass = std::move(kept);
    for (int ir = 0; ir < mesh_->nodes_r(); ++ir)
      symmetry_plane_.push_back(dofs_->u_z(mesh_->node_index(ir, 0)));
  }
  system_.set_end_mass(end_mass);
  const int nu = dofs_->n_u(), np = dofs_->n_phi();
  split_.m = system_.mass().topLeftCorner(nu, nu);
  split_.m_end = system_.end_mass().topLeftCorner(nu, nu);
  for (int i = 0; i < 5; ++i)
    split_.k_c[i] = system_.matrix(static_cast<MaterialParam>(i)).topLeftCorner(nu, nu);
  for (int i = 0; i < 3; ++i)
    split_.k_e[i] = system_.matrix(static_cast<MaterialParam>(5 + i)).block(0, nu, nu, np);
  for (int i = 0; i < 2; ++i)
    split_.k_eps[i] = system_.matrix(static_cast<MaterialParam>(8 + i)).bottomRightCorner(np, np);
}

std::unique_ptr<TubeModel> TubeModel::upper_half() const {
  if (extent_ != TubeExtent::whole)
    throw std::invalid_argument("TubeModel::upper_half: the model is already a half");
  const MeshOptions& o = mesh_->options();
  if (o.n_axial % 2 != 0) return nullptr;
  MeshOptions half_mesh = o;
  half_mesh.n_axial = o.n_axial / 2;
  TubeGeometry half = geometry_;
  half.length_m = 0.5 * geometry_.length_m;
  return std::make_unique<TubeModel>(half, half_mesh, gauss_points_, TubeExtent::upper_half);
}

SpMat TubeModel::mass(double f) const {
  if (f == 0.0) return split_.m;
  if (!std::isfinite(f) || f < 0.0)
    throw std::invalid_argument("TubeModel::mass: end_mass_fraction must be finite and >= 0");
  return split_.m + f * split_.m_end;
}

double TubeModel::tube_mass() const { return tube_mass_kg(geometry_); }

AssembledMatrices TubeModel::assemble(const PiezoMaterialE& material) const {
  validate(material, "TubeModel::assemble");
  const auto w = weights(material);
  AssembledMatrices a;
  a.m = split_.m;
  a.k_uu = w[0] * split_.k_c[0];
  for (int i = 1; i < 5; ++i) a.k_uu += w[i] * split_.k_c[i];
  a.k_uphi = w[5] * split_.k_e[0];
  for (int i = 1; i < 3; ++i) a.k_uphi += w[5 + i] * split_.k_e[i];
  a.k_phiphi = w[8] * split_.k_eps[0] + w[9] * split_.k_eps[1];
  return a;
}

Eigen::VectorXd TubeModel::mirror(const Eigen::VectorXd& u) const {
  Eigen::VectorXd p(u.size());
  for (int n = 0; n < mesh_->num_nodes(); ++n) {
    const int m = mesh_->mirror(n);
    p[dofs_->u_r(n)] = u[dofs_->u_r(m)];
    p[dofs_->u_z(n)] = -u[dofs_->u_z(m)];
  }
  return p;
}

double TubeModel::analytic_capacitance(double eps33) const {
  return 2.0 * M_PI * eps33 * geometry_.length_m /
         std::log(geometry_.outer_diameter_m / geometry_.inner_diameter_m);
}

}  // namespace piezo::model
