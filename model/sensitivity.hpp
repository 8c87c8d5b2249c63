#pragma once
// Seed Appendix C (C.1 d form, C.2 e form): how much each constant moves the
// tube's electrical behaviour. Each of the ten constants is scaled (doubled and halved) alone and
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

// Appendix C's three parameterisations of the same material, ten constants each:
//   d            sE11 sE12 sE13 sE33 sE44 d31 d33 d15 εT11 εT33 (Tables C.1, C.3)
//   engineering  YE11 YE33 ν12 ν13 G (sE13 = −ν13/YE33, eq 13) and the d-form's
//                piezoelectric and dielectric five (Table C.2)
//   e            cE11 cE12 cE13 cE33 cE44 e31 e33 e15 εS11 εS33 (Tables C.4, C.5)
enum class SensitivityForm { d, engineering, e };
const char* to_string(SensitivityForm f);  // "d", "engineering", "e"
enum class ParamGroup { elastic, piezoelectric, dielectric };
struct SensitivityParam {
  const char* name;
  ParamGroup group;
  // The seed's reading: d and engineering forms, eq 16 (sE11/YE11, sE12/ν12,
  // d31, εT33); e form, §C.2 (cE11, cE12, cE13, cE33, e31, e33, εS33).
  bool seed_says_sensitive;
};
const std::vector<SensitivityParam>& sensitivity_params(SensitivityForm f);
// The seed's own factor for a group: elastic doubled, piezoelectric and
// dielectric halved (Appendix C's text).
double seed_factor(ParamGroup g);

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
  SensitivityForm form = SensitivityForm::d;
  // The seed's protocol: each constant scaled by seed_factor of its group only
  // (`factors` unused), and a scaled material outside the physical domain
  // solved as it is (ModalSolver::set_physical_checks(false)) and flagged,
  // as the seed did (sE13 doubled, εT33 halved), instead of refused.
  bool seed_protocol = false;
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
  DParam param = DParam::s_e11;  // the d form's; index into sensitivity_params(form) for every form
  int index = 0;
  std::string name;              // sensitivity_params(form)[index].name
  double factor = 1;
  bool valid = false;  // physical and solved (the numbers below describe a real material)
  bool physical = true;   // false: the scaled material is outside the physical domain (reason says why)
  bool solved = false;    // the numbers below are filled (a non-physical case only with seed_protocol)
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
// valid = false, not an exception (solved and flagged with seed_protocol).
// `material` is the d form; options.form chooses what is scaled.
SensitivityResult form_sensitivity(const TubeGeometry& geometry, const PiezoMaterialD& material,
                                   const SensitivityOptions& options = {});
// form_sensitivity with the d form (Tables C.1, C.3).
SensitivityResult d_form_sensitivity(const TubeGeometry& geometry, const PiezoMaterialD& material,
                                     const SensitivityOptions& options = {});

}  // namespace piezo::model
