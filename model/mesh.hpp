#pragma once
// Structured r–z mesh of the tube cross-section (seed §3.2, Fig. 11b) with
// 9-node (biquadratic Lagrange) axisymmetric elements, and the DOF map:
// per node u_r, u_z and φ; φ = 0 on the inner surface (grounded electrode, no
// DOF), φ on the outer surface tied to ONE equipotential electrode DOF.
// z runs from −L/2 to L/2 so that z = 0 is the mid-plane of the seed.
#include <array>
#include <vector>

#include "model/tube_geometry.hpp"

namespace piezo::model {

// Refinement controls: elements through the wall (radial) and along the length.
struct MeshOptions {
  int n_radial = 2;
  int n_axial = 24;
  void validate() const;  // throws std::invalid_argument
  // Uniform refinement: every element split in two in both directions `level` times.
  MeshOptions refined(int level) const;
};

struct Node {
  double r = 0, z = 0;
};

class TubeMesh {
 public:
  TubeMesh(const TubeGeometry& g, const MeshOptions& opt);

  int num_nodes() const { return static_cast<int>(nodes_.size()); }
  int num_elements() const { return static_cast<int>(elements_.size()); }
  const std::vector<Node>& nodes() const { return nodes_; }
  // Local node a = 3·iz + ir (ir, iz ∈ {0,1,2} along r and z).
  const std::array<int, 9>& element(int e) const { return elements_[e]; }
  int nodes_r() const { return nr_; }  // node columns across the wall (2·n_radial + 1)
  int nodes_z() const { return nz_; }  // node rows along the length (2·n_axial + 1)
  int node_index(int ir, int iz) const { return iz * nr_ + ir; }
  bool on_inner_surface(int node) const { return node % nr_ == 0; }
  bool on_outer_surface(int node) const { return node % nr_ == nr_ - 1; }
  // Node mirrored about the mid-plane z = 0.
  int mirror(int node) const { return node_index(node % nr_, nz_ - 1 - node / nr_); }
  const MeshOptions& options() const { return opt_; }

 private:
  MeshOptions opt_;
  int nr_ = 0, nz_ = 0;
  std::vector<Node> nodes_;
  std::vector<std::array<int, 9>> elements_;
};

// Global numbering of the full system x = [U; Φ_int; V]:
//   U      u_r, u_z of node n at 2n, 2n+1 (n_u = 2·nodes)
//   Φ_int  potentials of nodes strictly inside the wall (n_i of them)
//   V      the outer electrode (last index); the inner electrode is ground.
// The potential block Φ = [Φ_int; V] has n_phi = n_i + 1 entries.
class DofMap {
 public:
  explicit DofMap(const TubeMesh& mesh);
  int n_u() const { return n_u_; }
  int n_phi() const { return n_phi_; }
  int n_total() const { return n_u_ + n_phi_; }
  int electrode() const { return n_total() - 1; }
  int u_r(int node) const { return 2 * node; }
  int u_z(int node) const { return 2 * node + 1; }
  // Global index of the potential of `node`, or −1 for a grounded node.
  int phi(int node) const { return phi_[node]; }

 private:
  int n_u_ = 0, n_phi_ = 0;
  std::vector<int> phi_;
};

}  // namespace piezo::model
