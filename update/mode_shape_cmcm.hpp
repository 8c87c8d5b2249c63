#pragma once
// Direct (non-iterative) CMCM with target mode shapes, seed Appendix D.
//
// With εS11 = 0 (the seed's assumption for D.2) K_ΦΦ = εS33 K_εS33 (eq. 246)
// and the condensed stiffness of either electrode condition (eq. 92) is
//   K = Σ_n cE_n K_cn  +  Σ_kl (e_k e_l / εS33) K_ek N⁻¹ K_elᵀ,   N = −K_εS33 (condensed rows),
// n over cE11, cE12, cE13, cE33, cE44 (eq. 234, D.1), k, l over e31, e33, e15
// (eq. 242). The coupling part is the seed's K3 = b1K6 + b2K7 + b3K8 +
// √(b1b2)K9 + √(b1b3)K10 + √(b2b3)K11 (D.3-D.9) with b1 = e31²/εS33,
// b2 = e33²/εS33, b3 = e15²/εS33 (the √ terms carry the sign of e_k e_l).
//
// The seed's D.10 writes the cross terms as √((1+α6)(1+α7)) etc. — not of the
// form of eq. 173. Here they are LIFTED: the three products e_k e_l/εS33 get
// coefficients of their own (α9, α10, α11), which makes K exactly linear in
// eleven unknowns, so exact target shapes give the exact answer in one TSVD
// solve (eqs 187-193) — no linearisation error. The rank-1 structure that
// the lifting ignores ((1+α9)² = (1+α6)(1+α7), …) is then imposed by a
// Gauss–Newton refinement on the eight physical unknowns (cE_n and
// g_k = e_k/√εS33) over the SAME equations (no further modal solve), which
// matters only for noisy shapes; `rank1_defect` reports how far the lifted
// answer was from it. D.11 separates e31, e33, εS33 with εT33 (closed form:
// εS33 = εT33/(1 + g·sE·g), g = (e31, e33)/√εS33). e15 comes out as
// g15·√εS33.
//
// Our FE model condenses potentials INSIDE the wall, so — unlike the seed's
// model — even the short-circuit stiffness carries the coupling terms
// (with the electrode grounded). Hence two stagings:
//   seed:  D.1 on the short-circuit modes for α1..α5 with the coupling held
//          at the base model's, then D.2 on the open-circuit modes for the
//          coupling with the elastic part fixed (moved to the right-hand side);
//          biased on our model by the short-circuit coupling change;
//   joint: all eleven unknowns from the short- and open-circuit equations
//          stacked (exact on our model). Default.
#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "model/modal.hpp"
#include "model/tube_model.hpp"

namespace piezo::update {

// Modes as the updater uses them: shapes (n_u × J, any scaling) and λ = ω².
struct ModalData {
  Eigen::MatrixXd shapes;
  Eigen::VectorXd lambda;
};
// The lowest `n` elastic modes of a modal result (the rigid translation, ω = 0, skipped).
ModalData elastic_modes(const model::ModalResult& r, int n);

// The "measured" side: shapes and eigenvalues of both electrode conditions and
// εT33 from the low-frequency capacitance (D.11).
struct ModeShapeTargets {
  ModalData short_circuit, open_circuit;
  double eps_t33 = 0;  // F/m
};

enum class ModeShapeStaging { seed, joint };
const char* to_string(ModeShapeStaging s);

struct ModeShapeCmcmOptions {
  ModeShapeStaging staging = ModeShapeStaging::joint;
  int n_model_modes = 12;      // lowest elastic modes of the base model per electrode condition
  double svd_rel_tol = 1e-10;  // eq. 193 truncation
  // Pairs with |Φ_iᵀMΦ*_j| < min_cross·‖Φ_i‖_M‖Φ*_j‖_M are skipped (no information, eq. 182
  // ill-posed).
  double min_cross = 1e-3;
  // Include the i ≠ j pairs (the seed: N_i × N_j equations). Their rows carry
  // the shape change (Φ_iᵀMΦ*_j is of the order of α) and so amplify any error
  // in the target shapes by 1/Φ_iᵀMΦ*_j; with i = j only, the 2 × 12 rows are
  // the eigenvalue equations evaluated with the target shapes (docs/update-methods.md).
  bool cross_modes = true;
  // The seed's D.10 read as eq. 173 by linearising √((1+α_k)(1+α_l)) ≈
  // 1 + (α_k + α_l)/2: eight unknowns, biased for large changes (kept to show
  // by how much; the default lifts the cross terms, exact).
  bool linearise_cross_terms = false;
  int refine_iterations = 20;  // Gauss–Newton on (cE_n, g_k); 0 keeps the lifted answer
  model::ModalOptions modal = [] {
    model::ModalOptions o;
    o.n_modes = 13;  // 12 elastic + the rigid translation
    return o;
  }();
};

// The unknowns, in order: α1..α5 (cE11, cE12, cE13, cE33, cE44; D.1), α6..α8
// (b1, b2, b3; D.10), α9..α11 (e31e33, e31e15, e33e15 over εS33; lifted).
inline constexpr int kModeShapeUnknowns = 11;
const char* mode_shape_unknown_name(int n);

// One linear system G α = f (eqs 182-190, β = 0: the mass is not updated).
struct ModeShapeEquations {
  Eigen::MatrixXd g;
  Eigen::VectorXd f;
  std::vector<int> unknowns;                  // columns of g → unknown index
  std::vector<model::Electrodes> electrodes;  // per row
  std::vector<std::pair<int, int>> pairs;     // per row (model mode i, target mode j)
  Eigen::VectorXd singular_values;
  Eigen::MatrixXd right_singular_vectors;  // columns: directions in α, largest σ first
  // Per column: fraction of its norm left after projection onto the other
  // columns (1 = independent, ≪ 1 = nearly a combination of the others).
  Eigen::VectorXd independence;
  int rank = 0;
};

struct ModeShapeCmcmResult {
  bool ok = false;
  std::string message;
  ModeShapeStaging staging = ModeShapeStaging::joint;
  std::array<double, kModeShapeUnknowns> alpha_lifted{};  // TSVD answer
  std::array<double, kModeShapeUnknowns> alpha{};         // after the rank-1 refinement
  double rank1_defect = 0;  // max_kl |(1+α_kl) − s·√((1+α_kk)(1+α_ll))| of the lifted answer
  int refine_iterations = 0;
  double residual_lifted = 0, residual = 0;  // ‖Gα − f‖ of each answer (all stages' rows)
  std::array<double, 3> b_base{}, b{};       // e31²/εS33, e33²/εS33, e15²/εS33
  std::array<double, 5> c_e{};               // updated cE11, cE12, cE13, cE33, cE44
  model::PiezoMaterialE updated;             // after D.11 (εS11 kept at 0)
  // One entry per linear solve: the joint system, or D.1 then D.2.
  std::vector<ModeShapeEquations> systems;
};

// Throws std::invalid_argument when the base material has εS11 ≠ 0 or a zero
// constant among the eight updated, or the targets are inconsistent.
ModeShapeCmcmResult mode_shape_cmcm(const model::TubeModel& tube, model::ModalSolver& solver,
                                    const model::PiezoMaterialE& base,
                                    const ModeShapeTargets& targets,
                                    const ModeShapeCmcmOptions& options = {});

// D.11 in SI: εS33 = εT33 − [2(s11+s12)e31² + 4 s13 e31 e33 + s33 e33²], with
// sE the inverse of the elastic matrix of `elastic` (its cE's are used).
// Given g = e/√εS33 it is linear in εS33: εS33 = εT33 / (1 + Q(g)).
double eps_s33_d11(const model::PiezoMaterialE& elastic, double g31, double g33, double eps_t33);

}  // namespace piezo::update
