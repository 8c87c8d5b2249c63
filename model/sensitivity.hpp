#pragma once
// Seed Appendix C.1: how much each d-form constant moves the tube's electrical
// behaviour. Each of the ten constants is scaled (doubled and halved) alone and
// the FE model re-solved: the relative change of every electrically active
// short-circuit frequency in the band (Tables C.1 / C.3 plot 0-200 kHz), of
// the active open-circuit (anti-resonance) frequencies and of the static
// capacitance. The seed's claim (eq 16, the thin-cylinder reduction T3 = T4 =
// T5 = 0): only sE11, sE12, d31 and εT33 matter. Computation only; the CLI
// (`piezobench model sensitivity`) prints the result.
#include <array>
#include <string>
#include <vector>

#include "model/material.hpp"
#include "model/mesh.hpp"
#include "model/tube_geometry.hpp"

namespace piezo::model {

// The ten d-form constants in seed Table 1 order.
enum class DParam : int { s_e11, s_e12, s_e13, s_e33, s_e44, d31, d33, d15, eps_t11, eps_t33 };
inline constexpr int kNumDParams = 10;
const char* d_param_name(DParam p);  // "sE11", …, "epsT33"
double& d_param(PiezoMaterialD& m, DParam p);
// The four the seed (eq 16) calls sensitive: sE11, sE12, d31, εT33.
bool seed_says_sensitive(DParam p);

struct SensitivityOptions {
  double band_hz = 200e3;  // upper band edge (Tables C.1, C.3: 0-200 kHz)
  std::vector<double> factors = {2.0, 0.5};
  MeshOptions mesh;  // default 2 × 24
  // Electrical-activity thresholds of the nominal modes, as in ModalOptions; open
  // circuit 1e-4 as the updaters use (the active anti-resonance modes of the presets
  // have ≥ 9.3e-3, the weak symmetric ones below 200 kHz ≤ 4e-5).
  double active_coupling = 1e-3;
  double active_coupling_open = 1e-4;
  // Perturbed modes are computed up to track_margin × band_hz, so a nominal mode
  // that a change pushes above the band edge is still found.
  double track_margin = 1.5;
  void validate() const;  // throws std::invalid_argument
};

// Active modes in the band and the static capacitance for one material.
struct ElectricalSignature {
  std::vector<double> short_hz;  // active short-circuit frequencies < band, ascending
  std::vector<double> open_hz;   // active open-circuit frequencies < band, ascending
  double c_static_f = 0;         // free tube, ω → 0
};

// One nominal active mode followed into the perturbed tube: the perturbed mode
// (symmetric, any coupling) whose shape is closest, MAC = (φ_nᵀ M φ_p)² with
// M-normalised shapes (M does not depend on the material). Pairing by shape, not
// by order: a weak mode crossing the activity threshold or the band edge would
// otherwise shift every later pair.
struct TrackedMode {
  double nominal_hz = 0;
  double perturbed_hz = 0;
  double change = 0;  // perturbed_hz / nominal_hz − 1
  double mac = 0;     // 1 = same shape; < 0.5 means the pairing is ambiguous
};

struct SensitivityCase {
  DParam param = DParam::s_e11;
  double factor = 1;
  bool valid = false;  // false: the scaled material is not physical (reason says why)
  std::string reason;
  ElectricalSignature perturbed;
  std::vector<TrackedMode> short_modes, open_modes;  // one per nominal active mode
  double c_static_change = 0;
  // max |change| over the tracked frequencies and C_static.
  double max_abs_change = 0;
  double min_mac = 1;  // smallest MAC of the pairings
};

struct SensitivityResult {
  bool converged = true;
  std::string message;  // first non-convergence, when !converged
  ElectricalSignature nominal;
  std::vector<SensitivityCase> cases;  // param-major, factors in option order
  // Largest max_abs_change over the valid cases of one parameter (0 if none valid).
  double max_change(DParam p) const;
  int valid_cases(DParam p) const;
};

// Throws std::invalid_argument (naming the function) for an invalid nominal
// material or geometry; a scaled material that is not physical is a case with
// valid = false, not an exception.
SensitivityResult d_form_sensitivity(const TubeGeometry& geometry, const PiezoMaterialD& material,
                                     const SensitivityOptions& options = {});

}  // namespace piezo::model
