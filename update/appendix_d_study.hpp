#pragma once
// Issue 22 item 4: seed Appendix D's numerical study (Table D.1) on our FE
// tube, and the three ways the program can update that tube side by side:
//   (a) mode-shape CMCM (update/mode_shape_cmcm, Appendix D) from the target's
//       shapes and eigenvalues, εT33 from the FE capacitance at f_L by eq. 201;
//   (b) the extended CMCM from frequencies (update_cmcm, §6.4: three
//       resonances, three anti-resonances, |Z(f_L)|), transversely isotropic
//       class with the original's insensitive constants;
//   (c) the output-error fit (fit_output_error) of a simulated divider capture
//       of the target (model::simulate_divider on its FE port model: the seed's
//       1 V exp_decay at 3000 1/s, R1 = 3140 Ω, 10 MS/s, 20000 samples), same class.
// Original and target are any e-form materials with εS11 = 0 (Appendix D.2).
#include <string>
#include <vector>

#include "model/material.hpp"
#include "model/modal.hpp"
#include "update/mode_shape_cmcm.hpp"
#include "update/output_error.hpp"
#include "update/updater.hpp"

namespace piezo::update {

// Table D.1's original and target (the seed's absolute e-form numbers).
model::PiezoMaterialE table_d1_original();
model::PiezoMaterialE table_d1_target();

struct AppendixDOptions {
  double noise_rel = 0.0;  // (c): std(noise)/std(clean) per channel (seed's definition)
  unsigned seed = 1;
  double beta_s = 6e-8;     // Rayleigh β of the simulated capture (fitted by (c))
  double f_low_hz = 400.0;  // f_L of the capacitance (εT33 for (a), |Z| for (b))
  ModeShapeCmcmOptions shapes;
  // (c) starts from (b)'s answer when (b) converged (the original of Table D.1
  // is too far from the target for the fit's own starts: see docs/update-methods.md),
  // else from the original.
  bool output_error_from_cmcm = true;
};

struct AppendixDRow {
  std::string name;                                           // cE11 … e15, epsT33
  std::string unit;                                           // as printed: GPa, ε0, C/m²
  double scale = 1;                                           // SI value / printed value
  double target = 0, shapes = 0, cmcm = 0, output_error = 0;  // SI
};

struct AppendixDStudy {
  std::vector<AppendixDRow> rows;
  double eps_t33_eq201 = 0;  // what (a) used for D.11
  // First three electrically active resonances / anti-resonances (Hz).
  ModelFrequencies f_original, f_target, f_shapes, f_cmcm, f_output_error;
  bool output_error_started_from_cmcm = false;
  ModeShapeCmcmResult shapes;
  UpdateResult cmcm;
  OeResult output_error;
  bool ok() const { return shapes.ok && cmcm.ok() && output_error.ok(); }
};

AppendixDStudy appendix_d_study(const model::TubeModel& tube, model::ModalSolver& solver,
                                const model::PiezoMaterialE& original,
                                const model::PiezoMaterialE& target,
                                const AppendixDOptions& options = {});

// The table as Markdown (what docs/update-methods.md carries).
std::string to_markdown(const AppendixDStudy& s);

}  // namespace piezo::update
