#pragma once
// The jobs' room (jobs/): the seed's 3-D and constrained FE checks (issue 44
// items 1–2), on model/circumferential.hpp.
//   `model three-d`     Table 3's 3-D column and Fig 17 (|Z| of the 2-D and 3-D
//                       models), the non-axisymmetric modes the 3-D model adds
//                       below f_max per harmonic n, and the exact torsion check.
//   `model constrained` Fig 19: the FE with u_z = 0 everywhere beside the free
//                       FE and the analytic ring (eq 40/41), with their |Z|.
// ui/cli/cmd_model_3d.cpp parses the options and prints.
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "jobs/model_job.hpp"

namespace piezo::jobs {

struct ThreeDRequest {
  ModelRequest model;
  double fmax_hz = 120e3;  // modes listed up to this frequency (Fig 14/17's band)
  int max_n = 0;           // highest harmonic; 0: up to the first with no mode below fmax_hz (≤ 32)
  double step_hz = 200;    // Fig 17's grid: step … fmax_hz
  double beta = 1e-7;      // Rayleigh β [s] of Fig 17 (the seed's chapter 5 value)
};

struct ImpedanceCurves {  // |Z| [Ω] on one grid, one column per curve
  std::vector<double> f_hz;
  std::vector<std::string> names;
  std::vector<std::vector<double>> abs_z;
};

struct ThreeDResult {
  nlohmann::json json;  // see docs/model-3d.md for every field
  ImpedanceCurves fig17;
};
// `progress(done, total)` after each harmonic. Throws std::invalid_argument /
// InputError for bad input, std::runtime_error when a solve fails.
ThreeDResult run_three_d(ThreeDRequest req, const std::function<void(int, int)>& progress = {});

struct ConstrainedRequest {
  ModelRequest model;
  double fmin_hz = 200, fmax_hz = 120e3, step_hz = 200;
  double beta = 1e-7;
};
struct ConstrainedResult {
  nlohmann::json json;
  ImpedanceCurves fig19;
};
ConstrainedResult run_constrained(ConstrainedRequest req);

// CSV f_hz,<name>_abs_ohm,… ; and a PNG or SVG (by the extension) of log |Z|.
void write_curves_csv(std::ostream& os, const ImpedanceCurves& c);
void write_curves_plot(const ImpedanceCurves& c, const std::string& title, const std::string& subtitle,
                       const std::filesystem::path& file);

}  // namespace piezo::jobs
