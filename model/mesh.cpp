#include "model/mesh.hpp"

#include <stdexcept>

namespace piezo::model {

void MeshOptions::validate() const {
  if (n_radial < 1) throw std::invalid_argument("MeshOptions::validate: n_radial must be >= 1");
  if (n_axial < 1) throw std::invalid_argument("MeshOptions::validate: n_axial must be >= 1");
  if (n_radial > 64 || n_axial > 4096)
    throw std::invalid_argument("MeshOptions::validate: mesh too fine (n_radial <= 64, n_axial <= 4096)");
}

MeshOptions MeshOptions::refined(int level) const {
  if (level < 0) throw std::invalid_argument("MeshOptions::refined: level must be >= 0");
  MeshOptions m = *this;
  m.n_radial <<= level;
  m.n_axial <<= level;
  return m;
}

TubeMesh::TubeMesh(const TubeGeometry& g, const MeshOptions& opt) : opt_(opt) {
  g.validate();
  opt.validate();
  nr_ = 2 * opt.n_radial + 1;
  nz_ = 2 * opt.n_axial + 1;
  const double ri = g.inner_radius(), ro = g.outer_radius(), len = g.length_m;
  nodes_.resize(static_cast<std::size_t>(nr_) * nz_);
  for (int iz = 0; iz < nz_; ++iz)
    for (int ir = 0; ir < nr_; ++ir) {
      // Exact end points; interior nodes evenly spaced.
      double r = ir == nr_ - 1 ? ro : ri + (ro - ri) * ir / (nr_ - 1);
      double z = iz == nz_ - 1 ? 0.5 * len : -0.5 * len + len * iz / (nz_ - 1);
      nodes_[node_index(ir, iz)] = {r, z};
    }
  for (int ez = 0; ez < opt.n_axial; ++ez)
    for (int er = 0; er < opt.n_radial; ++er) {
      std::array<int, 9> e{};
      for (int b = 0; b < 3; ++b)
        for (int a = 0; a < 3; ++a) e[3 * b + a] = node_index(2 * er + a, 2 * ez + b);
      elements_.push_back(e);
    }
}

DofMap::DofMap(const TubeMesh& mesh) {
  n_u_ = 2 * mesh.num_nodes();
  phi_.assign(mesh.num_nodes(), -1);
  int next = n_u_;
  for (int n = 0; n < mesh.num_nodes(); ++n)
    if (!mesh.on_inner_surface(n) && !mesh.on_outer_surface(n)) phi_[n] = next++;
  const int electrode = next;
  for (int n = 0; n < mesh.num_nodes(); ++n)
    if (mesh.on_outer_surface(n)) phi_[n] = electrode;
  n_phi_ = electrode + 1 - n_u_;
}

}  // namespace piezo::model
