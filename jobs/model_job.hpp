#pragma once
// The jobs' room (jobs/): `piezobench model materials|modal|impedance|sensitivity`
// — the FE tube model from a preset, its model class and --set overrides:
// short- and open-circuit modes, Z(f) (modal superposition or the direct
// solve) and the seed's Appendix C.1 sensitivity study, each with its JSON.
// ui/cli/cmd_model.cpp parses the options and prints.
#include <complex>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "model/material.hpp"
#include "model/mesh.hpp"
#include "model/sensitivity.hpp"
#include "model/tube_geometry.hpp"

namespace piezo::jobs {

// The tube: material preset, model class, overrides, mesh and geometry.
struct ModelRequest {
  std::string material = "apc850";
  bool isotropic = false;
  std::string set;
  int n_radial = model::MeshOptions{}.n_radial;
  int n_axial = model::MeshOptions{}.n_axial;
  model::TubeGeometry geometry;
};

// The request's material: e-form constants, model class ("isotropic" | "full")
// and the parameters as JSON; sets req.geometry's density from the preset.
// Throws std::invalid_argument (unknown preset, bad override).
struct ResolvedModel {
  model::PiezoMaterialE material;
  std::string model_class;
  nlohmann::json parameters;
};
ResolvedModel resolve_model(ModelRequest& req);

// `model materials`: [{name, description, density_kg_m3}] in the presets' order.
nlohmann::json materials_json();

struct ModalJobResult {
  nlohmann::json json;      // material, model_class, parameters, mesh, modes, C, converged
  std::string model_class;  // "isotropic" | "full"
  bool converged = false;
  std::string message;      // why not, when not converged
};
// Throws std::invalid_argument (unknown preset, bad override), InputError (modes outside 1..200,
// a plot name that is not .png or .svg). `shapes_plot` non-empty: the mode shapes drawn there
// (seed Figs 7, 12, 13; jobs/report/mode_shapes_plot.hpp).
ModalJobResult run_modal(ModelRequest req, int modes, const std::string& shapes_plot = "");

struct SweepRequest {
  double fmin = 0, fmax = 0, step = 0, alpha = 0, beta = 0;
  double qm = 0, tan_delta = 0;
  bool direct = false;
  int modes = 20;
};
struct ModelImpedanceResult {
  std::string model_class;
  std::vector<double> f_hz;
  std::vector<std::complex<double>> z_ohm;
};
// Throws InputError for a bad grid, std::invalid_argument for bad damping or
// losses, std::runtime_error when the modal solve does not converge.
ModelImpedanceResult run_model_impedance(ModelRequest req, const SweepRequest& sweep);
// {material, model_class, method, f_hz, re_ohm, im_ohm} (null where not finite).
nlohmann::json model_impedance_json(const ModelRequest& req, const SweepRequest& sweep,
                                    const ModelImpedanceResult& r);

struct SensitivityJobResult {
  model::SensitivityResult result;
  std::string model_class;
  nlohmann::json json;
};
struct SensitivityRequest {
  double band_hz = model::SensitivityOptions{}.band_hz;
  model::SensitivityForm form = model::SensitivityForm::d;  // --form d|engineering|e
  bool seed_protocol = false;                                // --seed-protocol
};
// Throws InputError for bad study options.
SensitivityJobResult run_sensitivity(ModelRequest req, const SensitivityRequest& study);

}  // namespace piezo::jobs
