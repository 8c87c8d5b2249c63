#include "jobs/pipeline/capture_fit.hpp"

#include <algorithm>
#include <cmath>
#include <mutex>
#include <optional>
#include <utility>

#include <stdexcept>

#include "model/material_presets.hpp"
#include "model/material_spec.hpp"
#include "model/modal.hpp"
#include "model/tube_model.hpp"

namespace piezo::jobs {

namespace {

// The last geometry's tube and upper half this process built (CaptureModel::tube).
struct SharedTube {
  std::mutex mutex;
  std::optional<model::TubeGeometry> geometry;
  std::shared_ptr<const model::TubeModel> whole, half;
  std::shared_ptr<model::PortModelMemo> memo;
};

bool same(const model::TubeGeometry& a, const model::TubeGeometry& b) {
  return a.inner_diameter_m == b.inner_diameter_m && a.outer_diameter_m == b.outer_diameter_m &&
         a.length_m == b.length_m && a.density_kg_m3 == b.density_kg_m3;
}

struct TubeOf {
  std::shared_ptr<const model::TubeModel> whole, half;
  std::shared_ptr<model::PortModelMemo> memo;
};
TubeOf tube_of(const model::TubeGeometry& g) {
  static SharedTube shared;
  std::lock_guard<std::mutex> lock(shared.mutex);
  if (!shared.geometry || !same(*shared.geometry, g)) {
    auto whole = std::make_shared<const model::TubeModel>(g);
    std::shared_ptr<const model::TubeModel> half = whole->upper_half();
    shared.memo = std::make_shared<model::PortModelMemo>(whole);
    shared.whole = std::move(whole);
    shared.half = std::move(half);
    shared.geometry = g;
  }
  return {shared.whole, shared.half, shared.memo};
}

}  // namespace

CaptureModel capture_model(const acq::Capture& cap, const std::string& material, bool isotropic) {
  CaptureModel m;
  m.nominal = model::resolve_material({material, isotropic, ""});
  model::TubeGeometry g = cap.setup.geometry();
  if (!cap.setup.density_kg_m3) g.density_kg_m3 = m.nominal.density_kg_m3;
  auto [whole, half, memo] = tube_of(g);
  m.tube = std::move(whole);
  m.solver = std::make_unique<model::ModalSolver>(*m.tube, std::move(half));
  // The port models of this process's captures of the tube (a lot's share the
  // nominal model and the coarse grid's, a capture's stages its answers'):
  // this capture's own reader of the memo, so that its work counts stay its
  // own (model/port_memo.hpp).
  m.solver->set_memo(std::move(memo), model::PortModelMemo::new_reader());
  m.cls = isotropic ? update::MaterialClass::isotropic()
                    : update::MaterialClass::transversely_isotropic(m.nominal.d);
  m.p0 = model::isotropic_params(m.nominal.d);
  return m;
}

CaptureFit fit_capture(const acq::Capture& cap, const CaptureFitRequest& req) {
  return fit_capture(cap, req, capture_model(cap, req.material, req.isotropic));
}

update::OeData capture_oe_data(const acq::Capture& cap, const std::optional<dsp::FixtureCalibration>& fixture,
                               std::string* excitation) {
  // The dut transient shots of the first one's drive.
  const acq::Shot* first = nullptr;
  for (const auto& s : cap.shots)
    if (s.role == acq::Role::Dut && s.excitation != acq::Excitation::Sine) {
      first = &s;
      break;
    }
  if (!first) throw std::invalid_argument("the capture holds no dut transient shot to fit");
  if (excitation) *excitation = std::string(acq::to_string(first->excitation));
  update::OeData data;
  data.sample_rate_hz = first->sample_rate_hz;
  data.circuit.r1_ohm = cap.setup.divider_r1_ohm;
  for (const auto& s : cap.shots) {
    if (s.role != acq::Role::Dut || s.excitation != first->excitation ||
        s.sample_rate_hz != first->sample_rate_hz)
      continue;
    data.shots.push_back({s.v1, s.v2, static_cast<std::size_t>(std::max<std::int64_t>(0, s.pretrigger_samples))});
  }
  if (fixture) {
    const auto& fx = *fixture;
    data.circuit.r1_ohm *= 1.0 + fx.r1_error.value_or(0.0);
    data.circuit.c_parallel_f = std::max(0.0, fx.fixture_capacitance_f.value_or(0.0));
    data.circuit.r_lead_ohm = std::max(0.0, fx.lead_resistance_ohm.value_or(0.0));
    data.v2_delay_s = fx.skew_s.value_or(0.0);
  }
  return data;
}

CaptureFit fit_capture(const acq::Capture& cap, const CaptureFitRequest& req, const CaptureModel& m) {
  CaptureFit out;
  update::OeOptions opts = req.options;
  const update::OeData data = capture_oe_data(cap, req.fixture, &out.excitation);
  out.shots_available = static_cast<int>(data.shots.size());
  if (req.fixture) {
    // Measured: their sigmas replace the stated tolerances — but a calibration
    // that cannot determine a quantity (a degenerate standard: the fixture
    // capacitance 0 ± 5e275 F beside a measured channel skew) never makes it
    // less known than the stated tolerance did: the smaller of the two.
    const auto& fx = *req.fixture;
    auto& o = opts;
    auto measured = [](const std::optional<double>& s, double stated) {
      if (!s || !std::isfinite(*s) || !(*s >= 0)) return stated;
      return stated > 0 ? std::min(*s, stated) : *s;
    };
    if (fx.r1_error) o.r1_rel_sigma = measured(fx.r1_error_sigma, o.r1_rel_sigma);
    if (fx.fixture_capacitance_f) o.cp_sigma_f = measured(fx.fixture_capacitance_sigma_f, o.cp_sigma_f);
    if (fx.skew_s) o.skew_sigma_s = measured(fx.skew_sigma_s, o.skew_sigma_s);
  }
  out.result = update::fit_output_error(*m.solver, m.cls, m.p0, data, opts);
  return out;
}

}  // namespace piezo::jobs
