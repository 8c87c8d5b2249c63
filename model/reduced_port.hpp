#pragma once
// A reduced-basis (Ritz) port model (issue 43 item 2): near a material x0,
// the port model (model/port_model.hpp) from a Galerkin projection of the
// coupled system on the exact solutions of a few nearby materials, in place
// of three sparse factorisations and a Lanczos run.
//
// The basis: at each snapshot material (x0 and points around it), the upper
// half's short-circuit mode shapes and static shape (U), and the interior
// potentials of each mode, of the static and of the clamped solution (Φ_int)
// — ModalSolver::port_vectors. U is made M-orthonormal, Φ_int orthonormal,
// and the electrode's V is kept as itself: W = [V_U, V_Φ, e_V]. The coupled
// stiffness is affine in the ten e-form constants (K = Σ w_p K_p, seed eqs
// 234, 242, 245), so each K_p is projected once, WᵀK_pW, and a material's
// reduced system is their weighted sum (d = r + q + 1 rows). From it, as the
// exact solver does on the full system (model/modal.cpp):
//   clamped (U = 0, V = 1):  y_c = −K_ΦΦ⁻¹K_ΦV,  C0 = −(K_VΦ y_c + K_VV),
//                            g = K_UΦ y_c + K_UV (the electrode load on U);
//   short circuit:           K_sc = K_UU − K_UΦ K_ΦΦ⁻¹ K_ΦU (Φ condensed),
//                            K_sc z = ω² M_r z, p = gᵀz, κ = zᵀK_UU z;
//   static (V = 1):          K_sc u_s = −g,  C_static = C0 + gᵀK_sc⁻¹g,
//                            u_sᵀ M u_s for the residual pseudo-mode.
// The projection is a Rayleigh–Ritz one on each side of the saddle (U raises
// ω², a restricted Φ lowers it), so its error is second order in how far the
// exact solutions at x lie from the basis: the frequencies agree with the
// Lanczos solve to its tolerance, the participations (first order in the
// shapes' error) to about 1e-8 within 1e-3 of x0 and 1e-6 within 2e-2
// (tests/model/test_reduced_port.cpp) — on the tubes we tried. Near a
// veering (two modes exchanging shapes within a percent of a constant) the
// basis misses the new shapes, so every answer carries its own check:
//   the residual of each Ritz pair in the exact, fully condensed system,
//   r = K_sc φ − ω²Mφ = r_U − K_UΦ K_ΦΦ⁻¹ r_Φ (r_U, r_Φ: the coupled
//   system's residual with the reduced potentials), η = ‖r‖_M⁻¹. Then
//   (Parlett, The Symmetric Eigenvalue Problem, §11-5) an exact eigenvalue
//   lies within |φᵀr| + η²/δ of ω² (the first term: the reduced
//   condensation's share of the Rayleigh quotient) and the shape within η/δ
//   of φ (δ: the gap to the next Ritz value); and to first order
//   Δp = −Σ_j p_j φ_jᵀr/(ω_j² − ω²), so |Δp| ≤ (Σ_j p_j²ω_j²/(ω_j² − ω²)²)^½
//   · (rᵀK_sc⁻¹r)^½ (Cauchy–Schwarz; the sum over the Ritz pairs, which
//   carry the whole static share C_static − C0).
// Both are first-order estimates, not bounds; the participation's uses
// K_sc at a reference material (ReducedPortSpace) for K_sc here (×2) and the Ritz values for the exact
// ones (×2). On the tubes of tests/model/test_reduced_port.cpp they exceed
// the errors — the participation's by 1e3–1e4 — and Bound::acceptable()
// takes |Δω|/ω ≤ 1e-7 and a participation estimate ≤ 1e-3 (errors measured
// ≤ 1e-6 there).
// port_model reports the worst over the modes that show in the port (p²/ω²
// above 1e-4 of C0); a caller that finds the answer not acceptable solves
// exactly. A veering the basis misses makes δ − η ≤ 0: refused. The end mass is the
// snapshots' (M(f) with their f). Immutable once built: thread-safe.
#include <Eigen/Core>
#include <Eigen/SparseCholesky>
#include <array>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "model/coupled_solver.hpp"
#include "model/material.hpp"
#include "model/modal.hpp"
#include "model/port_model.hpp"
#include "model/tube_model.hpp"

namespace piezo::model {

// What every basis on one upper half shares (built once per half, then
// shared): the split matrices' blocks (each lives in one block of K: the
// cE's on U×U, the e's on U×Φ, the εS's on Φ×Φ, with Φ = [Φ_int, V]), the
// mass and the end mass, and the factorisations the check needs (M with
// the mid-plane's u_z constrained; −K_ε33 on Φ_int, which is −K_ΦΦ/εS33
// for the isotropic class, εS11 = 0).
struct ReducedPortSpace {
  // `reference`: the material whose static short-circuit stiffness the check
  // takes for every basis's (ReducedPort::Bound; spectrally within a few
  // per cent of theirs where the bases are used). `estimates` false: without
  // the check's factorisations (for bases built without estimates). Throws
  // std::invalid_argument.
  ReducedPortSpace(std::shared_ptr<const TubeModel> half, const PiezoMaterialE& reference, bool estimates = true);
  std::shared_ptr<const TubeModel> model;
  bool estimates = true;  // the check's factorisations below made
  int nu = 0, np1 = 0;  // U DOFs; Φ DOFs with the electrode's V last
  std::array<SpMat, 5> k_uu;
  std::array<SpMat, 3> k_up, k_pu;  // (and transposed)
  std::array<SpMat, 2> k_pp;
  SpMat m, dm;  // M(0), ΔM (model/end_mass.hpp)
  Eigen::SimplicialLLT<SpMat> m_factor;
  Eigen::SimplicialLDLT<SpMat> eps33_factor;
  bool eps33_ok = false;
  std::vector<char> on_plane;  // the mid-plane's u_z (their residual is a reaction)
  std::shared_ptr<const CoupledFactor> static_factor;  // K(reference), σ = 0, V grounded
};

class ReducedPort {
 public:
  // From the snapshots' vectors (all on the same upper half; n_modes as
  // `opt`), about the material `centre` with the end mass
  // opt.end_mass_fraction; `space` shared with other bases on the same half
  // (null: made here, with `centre` its reference). nullopt when they are empty, live on different
  // models, or span fewer U directions than modes.
  // `estimates` false: a basis without them (port_model's bound then
  // infinite), a third less work to build and half the memory; a space made
  // without estimates serves only such bases.
  static std::optional<ReducedPort> build(std::span<const PortVectors> snapshots, const PiezoMaterialE& centre,
                                          const ModalOptions& opt,
                                          std::shared_ptr<const ReducedPortSpace> space = nullptr,
                                          bool estimates = true);
  // A snapshot: a material and the end mass to solve it with.
  struct Point {
    PiezoMaterialE material;
    double end_mass_fraction = 0;
  };
  // Its snapshots taken by `solver` (ModalSolver::port_vectors) at `points`,
  // the first the centre; nullopt when any fails (no upper half, a solve
  // that does not converge).
  static std::optional<ReducedPort> build(ModalSolver& solver, std::span<const Point> points,
                                          const ModalOptions& opt,
                                          std::shared_ptr<const ReducedPortSpace> space = nullptr,
                                          bool estimates = true);

  // The whole tube's port model at `material` with the end mass
  // `end_mass_fraction` (M(f) = M + f·ΔM is affine too: model/end_mass.hpp),
  // as ModalSolver::port_model with the options it was built with;
  // converged = false when the reduced system is not definite there (far
  // outside the basis's reach). `bound`, when given, receives the check.
  struct Bound {
    double omega = 0;          // worst relative |Δω|/ω ((|φᵀr| + η²/δ)/(2ω²))
    double participation = 0;  // worst relative |Δp|/|p| (above)
    bool acceptable() const;
  };
  static constexpr double kOmegaTolerance = 1e-7;
  static constexpr double kParticipationEstimate = 1e-3;
  ModalPortModel port_model(const PiezoMaterialE& material, double end_mass_fraction,
                            Bound* bound = nullptr) const;

  const std::shared_ptr<const ReducedPortSpace>& space() const { return space_; }

 private:
  ReducedPort() = default;
  // The check of port_model's answer `half` (before half_to_whole).
  Bound check(const MaterialWeights& w, double df, const Eigen::MatrixXd& x, const Eigen::VectorXd& g,
              const Eigen::MatrixXd& z, const Eigen::VectorXd& lambda, const ModalPortModel& half) const;

  std::shared_ptr<const ReducedPortSpace> space_;
  int r_ = 0, q_ = 0, n_modes_ = 0;
  double end_mass_ = 0;
  bool estimates_ = true;
  Eigen::MatrixXd v_u_;  // n_u × r, M(f₀)-orthonormal
  Eigen::MatrixXd v_p_;  // np1 × (q + 1): Φ_int's orthonormal basis, then V
  // The projected blocks, per constant: V_UᵀK V_U (r × r), V_UᵀK V_Φ
  // (r × (q + 1)), V_ΦᵀK V_Φ; and V_UᵀM(0)V_U, V_UᵀΔM V_U.
  std::array<Eigen::MatrixXd, 5> kuu_;
  std::array<Eigen::MatrixXd, 3> kup_;
  std::array<Eigen::MatrixXd, 2> kpp_;
  Eigen::MatrixXd m0_, dm_;
  // The check's: the blocks times the basis (K V), M(0)·V_U, ΔM·V_U.
  std::array<Eigen::MatrixXd, 5> kuu_v_;
  std::array<Eigen::MatrixXd, 3> kup_v_, kpu_v_;
  std::array<Eigen::MatrixXd, 2> kpp_v_;
  Eigen::MatrixXd mv_, dmv_;
};

}  // namespace piezo::model
