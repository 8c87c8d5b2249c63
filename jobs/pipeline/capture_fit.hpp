#pragma once
// The output-error estimator (update/output_error.hpp) on a capture: its dut
// transient shots of one drive, R1 and geometry from /setup, the nominal
// material of the model class — what `piezobench update CAP.h5 --method oe`,
// the pipeline and replay run.
#include <memory>
#include <optional>
#include <string>

#include "acquisition/capture.hpp"
#include "dsp/fixture_calibration.hpp"
#include "model/material_spec.hpp"
#include "model/modal.hpp"
#include "model/tube_model.hpp"
#include "update/output_error.hpp"

namespace piezo::jobs {

// The tube model of a capture: /setup's geometry (the material's density when
// the capture states none), the nominal material and the model class.
struct CaptureModel {
  model::ResolvedMaterial nominal;
  // Immutable, and shared with the other captures of this process that have
  // the same geometry (a lot of identical tubes in a batch: the whole tube and
  // its upper half are assembled once per geometry, not per capture).
  std::shared_ptr<const model::TubeModel> tube;
  std::unique_ptr<model::ModalSolver> solver;  // of *tube
  update::MaterialClass cls;
  update::TubeParams p0;  // the nominal material's four constants
};
CaptureModel capture_model(const acq::Capture& cap, const std::string& material, bool isotropic);

struct CaptureFitRequest {
  std::string material = "apc850";
  bool isotropic = true;
  update::OeOptions options;
  // A measured fixture (calibration shots): true R1, Cp at node 2, lead R
  // enter the divider the port is simulated in.
  std::optional<dsp::FixtureCalibration> fixture;
};

struct CaptureFit {
  update::OeResult result;
  std::string excitation;  // the drive of the shots used
  int shots_available = 0;
};

// The output-error data of a capture: its dut transient shots of the first
// one's drive and rate, R1 from /setup, corrected by a measured fixture (true
// R1, Cp, lead R, skew). `excitation` (optional) receives the drive's name.
// Throws std::invalid_argument when the capture holds no dut transient shot.
// The data's shots are views into `cap`: it must outlive them.
update::OeData capture_oe_data(const acq::Capture& cap, const std::optional<dsp::FixtureCalibration>& fixture,
                               std::string* excitation = nullptr);

// Throws std::invalid_argument when the capture holds no dut transient shot
// or the fit cannot use it.
CaptureFit fit_capture(const acq::Capture& cap, const CaptureFitRequest& req);
// The same on a tube model the caller already holds (capture_model of the
// same capture, material and class: the pipeline's).
CaptureFit fit_capture(const acq::Capture& cap, const CaptureFitRequest& req, const CaptureModel& model);

}  // namespace piezo::jobs
