// The jobs' room (jobs/): seed Appendix D's study (see mode_shape_job.hpp).
#include "jobs/mode_shape_job.hpp"

#include <vector>

#include "jobs/job_error.hpp"
#include "model/modal.hpp"
#include "model/tube_model.hpp"

namespace piezo::jobs {

namespace {

nlohmann::json freq_json(const update::ModelFrequencies& f) {
  return {{"resonances_hz", f.resonances_hz}, {"antiresonances_hz", f.antiresonances_hz}};
}

}  // namespace

ModeShapeResult run_mode_shape(const ModeShapeRequest& a) {
  update::AppendixDOptions o;
  if (!(a.capture_noise >= 0 && a.capture_noise < 1))
    throw InputError("--capture-noise must be in [0, 1)");
  o.noise_rel = a.capture_noise;
  o.seed = a.seed;
  if (a.staging == "joint")
    o.shapes.staging = update::ModeShapeStaging::joint;
  else if (a.staging == "seed")
    o.shapes.staging = update::ModeShapeStaging::seed;
  else
    throw InputError("--staging must be joint or seed");
  o.shapes.linearise_cross_terms = a.linearise;
  o.shapes.cross_modes = !a.diagonal;

  const model::TubeModel tube{model::TubeGeometry{}};
  model::ModalSolver solver(tube);
  const auto s = update::appendix_d_study(tube, solver, update::table_d1_original(),
                                          update::table_d1_target(), o);

  nlohmann::json j;
  j["rows"] = nlohmann::json::array();
  for (const auto& r : s.rows)
    j["rows"].push_back({{"name", r.name},
                         {"target", r.target},
                         {"mode_shape_cmcm", r.shapes},
                         {"extended_cmcm", r.cmcm},
                         {"output_error", r.output_error}});
  j["frequencies"] = {{"original", freq_json(s.f_original)},
                      {"target", freq_json(s.f_target)},
                      {"mode_shape_cmcm", freq_json(s.f_shapes)},
                      {"extended_cmcm", freq_json(s.f_cmcm)},
                      {"output_error", freq_json(s.f_output_error)}};
  nlohmann::json systems = nlohmann::json::array();
  for (const auto& eq : s.shapes.systems) {
    nlohmann::json unk = nlohmann::json::array();
    for (int u : eq.unknowns) unk.push_back(update::mode_shape_unknown_name(u));
    systems.push_back({{"equations", eq.g.rows()},
                       {"unknowns", unk},
                       {"rank", eq.rank},
                       {"singular_values", std::vector<double>(eq.singular_values.data(),
                                                               eq.singular_values.data() +
                                                                   eq.singular_values.size())}});
  }
  j["mode_shape_cmcm"] = {{"ok", s.shapes.ok},
                          {"message", s.shapes.message},
                          {"staging", update::to_string(s.shapes.staging)},
                          {"eps_t33_eq201", s.eps_t33_eq201},
                          {"rank1_defect", s.shapes.rank1_defect},
                          {"systems", systems}};
  j["extended_cmcm"] = {{"status", update::to_string(s.cmcm.status)}, {"message", s.cmcm.message}};
  j["output_error"] = {{"status", update::to_string(s.output_error.status)},
                       {"message", s.output_error.message},
                       {"chi2_per_dof", s.output_error.chi2_per_dof},
                       {"lack_of_fit", s.output_error.lack_of_fit},
                       {"started_from_extended_cmcm", s.output_error_started_from_cmcm},
                       {"capture_noise", a.capture_noise}};
  return {s, std::move(j)};
}

}  // namespace piezo::jobs
