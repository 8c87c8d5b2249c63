#pragma once
// The jobs' room (jobs/): `piezobench update Z.csv|Z.s1p [--resonances …]` —
// multi-physics FE model updating of the tube from impedance features (seed
// §6.3-6.4, docs/update-methods.md): extended CMCM, least squares (LM) or both, the
// Rayleigh damping from two modes and the |Z| overlay CSV. Explicit features
// override the ones found in the file. ui/cli/cmd_update.cpp parses the
// options and prints.
#include <functional>
#include <nlohmann/json.hpp>
#include <string>

#include "model/mesh.hpp"
#include "update/cmcm.hpp"

namespace piezo::jobs {

struct UpdateFeaturesRequest {
  std::string file;  // impedance file (CSV or Touchstone), optional with explicit features
  std::string resonances, antiresonances, low_z, material, set;
  std::string method;  // cmcm | lm | both
  std::string overlay, damping, capacitance = "fe";
  bool isotropic = false, cross_modes = false;
  // --seed-procedure: the seed's one pass (update::UpdateOptions::seed_procedure)
  // with its i != j equations (cross_modes on).
  bool seed_procedure = false;
  std::string history_plot;  // --history-plot: Figs 36-37 (α per CMCM iteration) as PNG/SVG
  int max_iterations = update::CmcmOptions{}.max_iterations;
  // --min-cross: i != j pairs with |Φ_iᵀMΦ*_j| below this share of the norms are left out
  // (update::CmcmOptions::min_cross); the seed's Fig 37 cycle depends on it (docs/update-methods.md).
  double min_cross = update::CmcmOptions{}.min_cross;
  int n_radial = model::MeshOptions{}.n_radial, n_axial = model::MeshOptions{}.n_axial;
  // Said at once: a damping fit from --damping that cannot be used.
  std::function<void(const std::string&)> warn;
};

struct UpdateFeaturesResult {
  nlohmann::json json;     // method, model_class, material, original, measured, updated, …
  std::string material;    // the preset's name
  bool converged = false;
};

// Throws InputError for bad options or an unreadable file, std::invalid_argument
// for a non-physical original model.
UpdateFeaturesResult run_update_features(const UpdateFeaturesRequest& req);

}  // namespace piezo::jobs
