#pragma once
// The tube in three dimensions by circumferential Fourier harmonics (issue 44
// item 1; the seed's 3-D SOLID226 model of §3.2.2, Table 3 and Fig 17).
//
// Geometry, material (4mm class, poled radially) and the full electrodes are
// all axisymmetric, so the 3-D field splits EXACTLY into harmonics in θ that
// do not couple: for harmonic n ≥ 0 and family s = ±1,
//   s = +1 ("cos"):  u_r = U_r cos nθ,  u_z = U_z cos nθ,  φ = Φ cos nθ,  u_θ = U_θ sin nθ
//   s = −1 ("sin"):  u_r = U_r sin nθ,  u_z = U_z sin nθ,  φ = Φ sin nθ,  u_θ = U_θ cos nθ
// with U_r, U_θ, U_z, Φ functions of (r, z) on the same 9-node r–z mesh as the
// 2-D model (model/mesh.hpp). In the IEEE axes of model/material.hpp (1 = z,
// 2 = θ, 3 = r) and with m = s·n, the 3-D strains and fields (seed eqs 102-105
// with the θ-derivatives kept) are
//   group A (∝ the family's cos/sin of U_r):
//     S1 = ∂U_z/∂z,  S2 = (U_r + m U_θ)/r,  S3 = ∂U_r/∂r,  S5 = ∂U_r/∂z + ∂U_z/∂r,
//     −E1 = ∂Φ/∂z,   −E3 = ∂Φ/∂r
//   group B (∝ the other one):
//     S4 = γ_θr = −m U_r/r + ∂U_θ/∂r − U_θ/r,   S6 = γ_zθ = ∂U_θ/∂z − m U_z/r,
//     −E2 = −m Φ/r
// The full 6×6 cE, 3×6 e and 3×3 εS of the class couple no A term with a B
// term, so the θ-integral of every energy product is a weight times the r–z
// integral: ∫cos² = π(1 + δ_n0), ∫sin² = π(1 − δ_n0). Hence:
//   * n = 0, s = +1 is the axisymmetric 2-D model exactly (U_θ carries no
//     energy and is removed): the 3-D model's axisymmetric modes ARE the 2-D
//     model's, which the tests check against model/modal.hpp (a second code);
//   * n = 0, s = −1 is torsion (U_θ only; U_r, U_z, Φ removed), electrically
//     inert; its modes are ω_k = kπ/L·√(cE66/ρ) exactly (u_θ = r cos(kπz/L));
//   * n ≥ 1: both families give the same frequencies (the pair of a mode and
//     its copy turned by π/2n), so s = +1 is solved. The full electrodes are
//     equipotential, so the n ≥ 1 harmonic of the potential vanishes on both:
//     Φ = 0 on the inner and outer surfaces in short AND open circuit — these
//     modes carry no charge and never show in the impedance (Fig 17).
// Free–free rigid motions are modes at 0 Hz: one per family at n = 0 (axial
// translation; rotation about z), two at n = 1 (translation across the axis;
// rocking), none at n ≥ 2 — a check of every θ-term above.
//
// The internal potentials (and, for n = 0 in open circuit, the electrode V) are
// condensed statically (eq. 92); the eigenproblem K_c φ = ω² M φ is solved
// DENSE for all modes (Eigen's generalised self-adjoint solver), which keeps
// this a reference: no truncation, no residual mode. Cost O(n_u³): on the
// default mesh (2 × 24 elements, 735 displacement DOFs at n ≥ 1) 1.5–3 s per
// harmonic, 0.5 s at n = 0; with max_frequency_hz only the modes below it, by
// shift-invert Lanczos on the same matrices. Meshes above kMaxDenseDofs are refused.
//
// `axial_constrained` clamps u_z at every node: the seed's "constrained" FE of
// Fig 19 (§3.3.1, "does not allow movements in the axial direction for all
// elements"), compared there with the analytic ring (model/analytic_ring.hpp).
#include <Eigen/Core>
#include <string>
#include <vector>

#include "model/coupled_solver.hpp"  // Electrodes
#include "model/material.hpp"
#include "model/mesh.hpp"
#include "model/port_model.hpp"
#include "model/tube_geometry.hpp"

namespace piezo::model {

inline constexpr int kMaxDenseDofs = 6000;

enum class HarmonicFamily { cos_family, sin_family };  // s = +1, s = −1 above
const char* to_string(HarmonicFamily f);

struct CircumferentialOptions {
  int n = 0;                                        // harmonic order, 0 … 64
  HarmonicFamily family = HarmonicFamily::cos_family;
  Electrodes electrodes = Electrodes::short_circuit;  // matters for n = 0, cos family only
  bool axial_constrained = false;                   // u_z = 0 everywhere (Fig 19)
  MeshOptions mesh{};
  int gauss_points = 3;
  // 0: every mode (dense, the reference). > 0: only the modes up to this
  // frequency (and at least the first one above it), by Spectra's shift-invert
  // Lanczos on the same dense condensed matrices — about ten times faster per
  // harmonic; the dense path is used anyway below 200 DOFs.
  double max_frequency_hz = 0;
  void validate() const;  // throws std::invalid_argument naming the field
};

struct CircumferentialMode {
  double frequency_hz = 0;   // 0 for a rigid motion (|ω²| below the rigid threshold)
  double omega = 0;          // rad/s
  double eigenvalue = 0;     // ω² as computed
  bool rigid = false;
  // p_k = gᵀφ_k (C per unit modal coordinate), g the shorted electrode's load
  // vector (in open circuit too, as model/modal.hpp); 0 unless n = 0, cos family.
  double participation = 0;
  double kappa = 0;          // φ_kᵀ K_UU φ_k (uncondensed, for βK_UU damping)
  // Share of the mode's kinetic energy in u_r, u_θ, u_z (sums to 1).
  double radial_share = 0, hoop_share = 0, axial_share = 0;
  bool symmetric = false;    // about the mid-plane (U_r even in z, U_z odd)
};

struct CircumferentialResult {
  CircumferentialOptions options;
  int n_u = 0;               // displacement DOFs solved
  int n_condensed = 0;       // potentials condensed
  double c_clamped = 0;      // C0 of the whole tube (n = 0, cos family, either circuit), F; else 0
  std::vector<CircumferentialMode> modes;  // all of them, ascending
  Eigen::MatrixXd shapes;    // n_u × modes, M-normalised (only when asked for)

  // All elastic modes as a port model (n = 0, cos family, short circuit):
  // exact, so no residual mode and C_static = C0 + Σ p_k²/ω_k².
  ModalPortModel port_model(const PiezoMaterialE& material) const;
};

// Throws std::invalid_argument for a bad geometry, material or option, and
// std::runtime_error when the dense solve fails (named, with the next step).
CircumferentialResult circumferential_modes(const TubeGeometry& geometry, const PiezoMaterialE& material,
                                            const CircumferentialOptions& options, bool keep_shapes = false);

// Torsional mode k ≥ 1 of the free–free tube, exact: f = k/(2L)·√(cE66/ρ),
// cE66 = (cE11 − cE12)/2.
double torsion_frequency_hz(const TubeGeometry& geometry, const PiezoMaterialE& material, int k);

}  // namespace piezo::model
