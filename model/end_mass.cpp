#include "model/end_mass.hpp"

#include <cmath>

#include "model/element.hpp"

namespace piezo::model {

double tube_mass_kg(const TubeGeometry& g) {
  g.validate();
  const double ri = g.inner_radius(), ro = g.outer_radius();
  return g.density_kg_m3 * M_PI * (ro * ro - ri * ri) * g.length_m;
}

std::vector<Eigen::Triplet<double>> end_face_mass_triplets(const TubeMesh& mesh, const DofMap& dofs,
                                                           const TubeGeometry& g) {
  const double ri = g.inner_radius(), ro = g.outer_radius();
  // Areal density for f = 1: half the tube mass on each face's annulus (= ρL/2).
  const double mu = 0.5 * tube_mass_kg(g) / (M_PI * (ro * ro - ri * ri));
  const GaussRule q = gauss_legendre(3);
  std::vector<Eigen::Triplet<double>> trip;
  const int n_edges = (mesh.nodes_r() - 1) / 2;
  trip.reserve(static_cast<std::size_t>(2 * n_edges * 9 * 2));
  for (const int iz : {0, mesh.nodes_z() - 1}) {
    for (int e = 0; e < n_edges; ++e) {
      int node[3];
      double r[3];
      for (int a = 0; a < 3; ++a) {
        node[a] = mesh.node_index(2 * e + a, iz);
        r[a] = mesh.nodes()[node[a]].r;
      }
      double m[3][3] = {};
      for (int k = 0; k < q.n; ++k) {
        const auto n = lagrange2(q.x[k]);
        const auto dn = lagrange2_deriv(q.x[k]);
        double rr = 0, dr = 0;
        for (int a = 0; a < 3; ++a) {
          rr += n[a] * r[a];
          dr += dn[a] * r[a];
        }
        const double da = 2.0 * M_PI * rr * std::abs(dr) * q.w[k];  // dA = 2πr dr
        for (int a = 0; a < 3; ++a)
          for (int b = 0; b < 3; ++b) m[a][b] += mu * n[a] * n[b] * da;
      }
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) {
          trip.emplace_back(dofs.u_r(node[a]), dofs.u_r(node[b]), m[a][b]);
          trip.emplace_back(dofs.u_z(node[a]), dofs.u_z(node[b]), m[a][b]);
        }
    }
  }
  return trip;
}

}  // namespace piezo::model
