#pragma once
// The jobs' room (jobs/): `piezobench model mode-shape-cmcm` — seed Appendix
// D's numerical study (Table D.1) on the default tube: mode-shape CMCM beside
// the extended CMCM and the output-error fit (update/appendix_d_study.hpp),
// and its JSON. ui/cli/cmd_model_mode_shape.cpp parses the options and prints.
#include <nlohmann/json.hpp>
#include <string>

#include "update/appendix_d_study.hpp"

namespace piezo::jobs {

struct ModeShapeRequest {
  double capture_noise = 0.0;
  unsigned seed = 1;
  std::string staging = "joint";  // joint | seed
  bool linearise = false;
  bool diagonal = false;
};

struct ModeShapeResult {
  update::AppendixDStudy study;
  nlohmann::json json;  // rows, frequencies, mode_shape_cmcm, extended_cmcm, output_error
};

// Throws InputError for a noise outside [0, 1) or an unknown staging.
ModeShapeResult run_mode_shape(const ModeShapeRequest& req);

}  // namespace piezo::jobs
