// The pipeline's room (jobs/pipeline), calibrate stage: the fixture measured
// from the capture's calibration shots (open, short, load), when it has any.
#include <algorithm>
#include <cstdio>

#include "acquisition/capture_calibration.hpp"
#include "jobs/pipeline/stages.hpp"

namespace piezo::jobs::detail {

// The fixture from the capture's calibration shots, when it has any. A
// failure is a warning: the transducer's shots are still estimated, uncorrected.
void calibrate_stage(const acq::Capture& cap, PipelineResult& out) {
  const bool any = std::any_of(cap.shots.begin(), cap.shots.end(), [](const acq::Shot& s) { return s.role != acq::Role::Dut; });
  if (!any) return;
  try {
    acq::CaptureCalibrationOptions co;
    co.fmax_hz = std::min(120e3, cap.shots.front().sample_rate_hz / 4);
    auto c = acq::calibrate_from_capture(cap, co);
    if (!c) return;
    out.fixture = c->fixture;
    out.fixture_model = c->model_description;
    const auto& f = c->fixture;
    char note[300];
    std::snprintf(note, sizeof note, "fixture from %s: Cp %.1f pF, lead R %.2f ohm, R1 error %+.3f %%, skew %.1f ns",
                  c->model_description.c_str(), f.fixture_capacitance_f.value_or(0) * 1e12,
                  f.lead_resistance_ohm.value_or(0), f.r1_error.value_or(0) * 100, f.skew_s.value_or(0) * 1e9);
    out.stages.push_back({"calibrate", true, note});
    for (const auto& n : c->notes) out.warnings.push_back("fixture calibration: " + n);
  } catch (const std::exception& e) {
    out.stages.push_back({"calibrate", false, std::string("failed: ") + e.what()});
    out.warnings.push_back(std::string("fixture calibration failed (") + e.what() +
                           "); the transducer's shots are used without fixture correction");
  }
}

}  // namespace piezo::jobs::detail
