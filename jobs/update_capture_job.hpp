#pragma once
// The jobs' room (jobs/): `piezobench update CAP.h5 [--method oe|cmcm|lm|all]`
// — the tube's constants straight from a capture. oe: the output-error fit of
// the FE port model to the recorded samples (jobs/pipeline/capture_fit.hpp),
// with a sigma and a status per constant; cmcm / lm: the seed's chain
// (Prony-SS features, extended CMCM or least squares on them); all: every
// method side by side, oe's the top-level answer. ui/cli/cmd_update_capture.cpp
// prints it.
#include <functional>
#include <nlohmann/json.hpp>
#include <string>

#include "update/output_error.hpp"

namespace piezo::jobs {

struct UpdateCaptureRequest {
  std::string file;
  std::string method = "oe";  // oe | cmcm | lm | all
  std::string material;       // empty: the capture's own (jobs/nominal_material.hpp)
  bool isotropic = true;
  update::OeOptions oe;
  // How the nominal material was chosen when it was a guess (said at once,
  // before the fit runs).
  std::function<void(const std::string&)> warn;
};

struct UpdateCaptureResult {
  nlohmann::json json;     // capture, method, model_class, material, original, the lead method's fields
  nlohmann::json methods;  // per method: oe, cmcm, lm
  std::string material;    // the nominal material used
  bool converged = false;  // of the lead method
};

// Throws InputError for an unknown method or a capture the fit cannot use,
// std::invalid_argument for an unknown material.
UpdateCaptureResult run_update_capture(const UpdateCaptureRequest& req);

}  // namespace piezo::jobs
