#include "model/outer_surface_damping.hpp"

#include <cmath>

#include "model/element.hpp"

namespace piezo::model {

namespace {

// The 3×3 edge matrix ∫ N_a N_b 2π r dz of outer edge e (nodes 2e, 2e+1, 2e+2
// of the outer node column), and its global nodes.
void outer_edge(const TubeMesh& mesh, int e, int node[3], double m[3][3]) {
  const GaussRule q = gauss_legendre(3);
  const int ir = mesh.nodes_r() - 1;
  double z[3], r[3];
  for (int a = 0; a < 3; ++a) {
    node[a] = mesh.node_index(ir, 2 * e + a);
    z[a] = mesh.nodes()[node[a]].z;
    r[a] = mesh.nodes()[node[a]].r;
  }
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) m[a][b] = 0.0;
  for (int k = 0; k < q.n; ++k) {
    const auto n = lagrange2(q.x[k]);
    const auto dn = lagrange2_deriv(q.x[k]);
    double rr = 0, dz = 0;
    for (int a = 0; a < 3; ++a) {
      rr += n[a] * r[a];  // = r_o on the straight outer edge
      dz += dn[a] * z[a];
    }
    const double da = 2.0 * M_PI * rr * std::abs(dz) * q.w[k];  // dA = 2π r_o dz
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) m[a][b] += n[a] * n[b] * da;
  }
}

}  // namespace

std::vector<Eigen::Triplet<double>> outer_surface_damping_triplets(const TubeMesh& mesh,
                                                                   const DofMap& dofs) {
  std::vector<Eigen::Triplet<double>> trip;
  const int n_edges = (mesh.nodes_z() - 1) / 2;
  trip.reserve(static_cast<std::size_t>(9 * n_edges));
  for (int e = 0; e < n_edges; ++e) {
    int node[3];
    double m[3][3];
    outer_edge(mesh, e, node, m);
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) trip.emplace_back(dofs.u_r(node[a]), dofs.u_r(node[b]), m[a][b]);
  }
  return trip;
}

double outer_surface_modal_damping(const TubeMesh& mesh, const DofMap& dofs,
                                   const Eigen::VectorXd& phi) {
  const int n_edges = (mesh.nodes_z() - 1) / 2;
  double c = 0.0;
  for (int e = 0; e < n_edges; ++e) {
    int node[3];
    double m[3][3];
    outer_edge(mesh, e, node, m);
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) c += phi[dofs.u_r(node[a])] * m[a][b] * phi[dofs.u_r(node[b])];
  }
  return c;
}

}  // namespace piezo::model
