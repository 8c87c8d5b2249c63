#pragma once
// Modal analysis of the tube with short-circuited (V = 0, eq. 88) or
// open-circuited (zero net charge, static condensation eq. 92) electrodes:
// the lowest N modes of (K_cond − ω²M) U = 0 by shift-invert Lanczos
// (Spectra), in the standard form of the Cholesky factor P M Pᵀ = L Lᵀ
// (operator Lᵀ P (K_cond − σM)⁻¹ Pᵀ L), where (K_cond − σM)⁻¹ is applied by
// solving the full coupled system (internal potentials condensed
// implicitly). The mechanical
// boundary is free–free, so mode 0 is the rigid axial translation (0 Hz).
//
// Per mode: frequency, M-normalised shape, symmetry about the mid-plane, and
// electrical participation p_k = gᵀφ_k (whether it shows up in the impedance).
#include <Eigen/Core>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "model/column_dots.hpp"
#include "model/coupled_solver.hpp"
#include "model/port_memo.hpp"
#include "model/port_model.hpp"
#include "model/tube_model.hpp"

namespace piezo::model {

struct ModalOptions {
  int n_modes = 10;
  // σ = −(2π·shift_hz)²: below the rigid-body mode, so the N lowest modes are
  // the N largest eigenvalues of the shift-inverted operator (the whole tube;
  // the upper half has no rigid mode and is solved at σ = 0).
  double shift_hz = 1000.0;
  int ncv = 0;  // Lanczos basis size; 0 → max(2N + 1, N + 20) (capped at n_u)
  double tolerance = 1e-10;
  int max_iterations = 1000;
  // A mode is electrically active if it is symmetric about the mid-plane and
  // its coupling p_k²/(ω_k² C0) exceeds this (see model/README.md); in open
  // circuit the second threshold applies (the updaters lower it: the
  // open-circuit partner of a strongly coupled mode carries little charge).
  double active_coupling = 1e-3;
  double active_coupling_open = 1e-3;
  // End-face mass loading (effect `mass_loading`): added mass as a fraction f of
  // the tube mass, M → M + f·ΔM (model/end_mass.hpp). ΔM is built once with the
  // TubeModel, so any f costs no re-assembly. Must be finite and >= 0.
  double end_mass_fraction = 0.0;
  // port_model() only: compute the port on the tube's upper half with u_z = 0 on
  // the mid-plane (TubeExtent::upper_half) — the antisymmetric modes carry no
  // charge (p_k = 0 by symmetry), so the port is the same on half the DOFs and
  // with n_modes/2 + 1 symmetric modes (a superset of the symmetric ones among
  // the whole tube's n_modes for the tubes we know; the residual mode takes
  // the rest either way). ~3x faster; ignored when a ModalResult is asked for
  // or the mesh has an odd number of axial elements.
  bool mirror_symmetry = true;
  // port_model() only, a SIMULATOR input (issue 21, out of the effect
  // catalogue): characteristic impedance Z_a (Pa·s/m, water ≈ 1.48e6) of a
  // fluid loading the outer cylindrical surface as a radial dashpot
  // (model/outer_surface_damping.hpp). Each elastic mode gets
  // PortMode::radiation_damping = Z_a·φ_kᵀ C_a1 φ_k; the residual pseudo-mode
  // gets none. 0 (default) leaves every result unchanged. Finite, >= 0.
  double outer_surface_impedance = 0.0;
  void validate() const;
};

enum class Symmetry { symmetric, antisymmetric, mixed };
const char* to_string(Symmetry s);
const char* to_string(Electrodes e);

struct Mode {
  double frequency_hz = 0;
  double omega = 0;                // rad/s (0 for the rigid-body mode)
  double eigenvalue = 0;           // ω² as computed (may be ~ −0 for the rigid mode)
  Symmetry symmetry = Symmetry::mixed;
  double symmetric_fraction = 0;   // ‖sym part‖²_M / ‖φ‖²_M, 1 = symmetric, 0 = antisymmetric
  double participation = 0;        // p_k = gᵀφ_k  (C per unit modal coordinate)
  double coupling = 0;             // p_k² / (ω_k² C0); 0 for the rigid mode
  double kappa = 0;                // φ_kᵀ K_UU φ_k
  bool electrically_active = false;
};

struct ModalResult {
  Electrodes electrodes = Electrodes::short_circuit;
  bool converged = false;   // all requested modes converged
  int n_converged = 0;
  std::string message;      // why not, when !converged
  std::vector<Mode> modes;  // ascending frequency
  Eigen::MatrixXd shapes;   // n_u × modes.size(), φᵀM(f)φ = I, M(f) = M + f·ΔM
  double end_mass_fraction = 0;  // f the modes were computed with
  double c_clamped = 0;     // C0 (F)

  // Electrically active modes (symmetric, coupling above threshold), ascending.
  std::vector<double> active_frequencies_hz() const;
};

// What a reduced port model (model/reduced_port.hpp) is built from: at one
// material, the upper half's short-circuit mode shapes and its static shape
// (V = 1) in `u`, and in `phi` the interior potentials Φ_int that go with
// each mode, with the static solution and with the clamped one (U = 0, V = 1)
// — the full coupled solutions, so that a Galerkin projection of the coupled
// system on them condenses Φ as the exact solver does.
struct PortVectors {
  std::shared_ptr<const TubeModel> model;  // the upper half they live on
  double end_mass_fraction = 0;            // the end mass they were solved with
  Eigen::MatrixXd u;    // n_u × (modes + 1), zero on the mid-plane's u_z
  Eigen::MatrixXd phi;  // (n_phi − 1) × (modes + 2): the electrode's V excluded
};

// Holds the symbolic factorisation: construct once per TubeModel and call for
// as many materials as needed. Not thread-safe (one solver per thread).
class ModalSolver {
 public:
  explicit ModalSolver(const TubeModel& model);
  // A solver on `model` whose port models use `half`, the upper half of
  // `model` as model.upper_half() builds it (or nullptr: the whole tube), instead
  // of building their own: a second solver for another thread shares its
  // first's (a TubeModel is immutable once built; issue 43).
  ModalSolver(const TubeModel& model, std::shared_ptr<const TubeModel> half);
  // The upper half this solver's port models use (built on the first call), or
  // nullptr when the mesh has no mid-plane row or the model is a half already.
  std::shared_ptr<const TubeModel> half_model();

  ModalResult solve(const PiezoMaterialE& material, Electrodes electrodes,
                    const ModalOptions& options = {});

  // Clamped capacitance C0 (U = 0) and the electrode load vector g (n_u).
  double clamped_capacitance(const PiezoMaterialE& material, Eigen::VectorXd* g = nullptr);
  // Capacitance of the free tube at ω → 0 (static solve, rigid mode clamped);
  // optionally the static displacement for V = 1, rigid translation removed.
  double static_capacitance(const PiezoMaterialE& material, Eigen::VectorXd* u_static = nullptr);
  // Short-circuit modes + C0 + C_static (+ residual mode) → the electrical port
  // model; with options.end_mass_fraction for a mass-loaded tube (C0 and
  // C_static do not depend on the mass; the modes and the residual mode do).
  // With a memo of this solver's tube (set_memo), a model asked for before
  // (by any solver sharing the memo) is taken from it, the same bits.
  ModalPortModel port_model(const PiezoMaterialE& material, const ModalOptions& options = {},
                            ModalResult* sc_result = nullptr);

  // The port models of this tube remembered across solvers, stages and
  // captures (model/port_memo.hpp); ignored if it is another tube's.
  // `reader`: whose work the solves count as (PortModelMemo::new_reader()).
  void set_memo(std::shared_ptr<PortModelMemo> memo, long reader = 0) {
    memo_ = std::move(memo);
    memo_reader_ = reader;
  }
  const std::shared_ptr<PortModelMemo>& memo() const { return memo_; }
  long memo_reader() const { return memo_reader_; }

  // The vectors of the port model at `material` (options as port_model's:
  // the half's n_modes/2 + 1 modes), for a reduced port model; nullopt when
  // port_model would not compute on the upper half (mirror_symmetry off, no
  // mid-plane node row, an outer-surface load) or the modal solve did not
  // converge. One modal solve and two static ones.
  std::optional<PortVectors> port_vectors(const PiezoMaterialE& material, const ModalOptions& options);

  const TubeModel& model() const { return *model_; }

  // Off: a material outside the physical domain (cE not positive definite,
  // εS33 ≤ 0) is solved as it is, finite constants only — the seed's own
  // non-physical perturbations of Appendix C (model/sensitivity.hpp), whose
  // results are flagged there. On by default; every other caller keeps it on.
  void set_physical_checks(bool on) { physical_checks_ = on; }

 private:
  void check(const PiezoMaterialE& material, const char* caller) const;
  // M + f·ΔM (cached for the last f).
  const SpMat& mass(double end_mass_fraction);
  // Its sparse Cholesky factor P·M(f)·Pᵀ = L·Lᵀ (cached for f = 0 and the last
  // f): the standard form of the shift-invert problem (solve()).
  struct MassFactor {
    double fraction = -1.0;
    SpMat l;                     // L, column-major (the eigenvectors' back-substitution)
    ColumnDots l_dots, lt_dots;  // the products with Lᵀ and L, a dot product per column of L and of Lᵀ (model/column_dots.hpp)
    Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> p, p_inv;
  };
  const MassFactor& mass_factor(double end_mass_fraction);
  // Static solve for V = 1 with the rigid translation fixed; u_static is made
  // M-orthogonal to the rigid mode for the given mass matrix.
  double static_solve(const PiezoMaterialE& material, const SpMat& mass, Eigen::VectorXd* u_static);

  // port_model without the memo.
  ModalPortModel solve_port_model(const PiezoMaterialE& material, const ModalOptions& opt, ModalResult* sc_result);
  // port_vectors on this solver's own model (the upper half).
  std::optional<PortVectors> own_port_vectors(const PiezoMaterialE& material, const ModalOptions& opt);
  // Port model of the upper half (TubeExtent::upper_half), scaled to the whole tube.
  ModalPortModel half_port_model(const PiezoMaterialE& material, const ModalOptions& opt);

  const TubeModel* model_;
  CoupledFactor factor_;
  std::shared_ptr<const TubeModel> half_model_;  // built on first use (mirror_symmetry), or shared
  std::unique_ptr<ModalSolver> half_solver_;
  bool half_tried_ = false;
  bool physical_checks_ = true;
  std::shared_ptr<PortModelMemo> memo_;
  long memo_reader_ = 0;
  SpMat m_uu_, k_uu_;
  SpMat m_loaded_;
  double m_loaded_fraction_ = -1.0;
  MassFactor m_factor_unloaded_, m_factor_loaded_;
  bool keep_clamped_ = false;      // clamped_capacitance keeps its solution in clamped_x_
  Eigen::VectorXd clamped_x_;
};

}  // namespace piezo::model
