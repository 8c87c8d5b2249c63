// `piezobench model mode-shape-cmcm`: seed Appendix D's numerical study
// (Table D.1) on the default tube — mode-shape CMCM beside the extended CMCM
// and the output-error fit (update/appendix_d_study.hpp). A thin shell: the
// study is domain logic in update/.
//   model mode-shape-cmcm [--capture-noise R] [--seed N] [--staging joint|seed]
//                         [--linearise-cross-terms] [--diagonal-pairs] [--json]
// Exit codes: 0 ok, 2 bad input, 1 when the mode-shape update fails.
#include <cstdio>

#include "model/modal.hpp"
#include "model/tube_model.hpp"
#include "ui/cli/cli_common.hpp"
#include "update/appendix_d_study.hpp"

namespace piezo::cli {

namespace {

struct ModeShapeArgs {
  double capture_noise = 0.0;
  unsigned seed = 1;
  std::string staging = "joint";
  bool linearise = false;
  bool diagonal = false;
};

nlohmann::json freq_json(const update::ModelFrequencies& f) {
  return {{"resonances_hz", f.resonances_hz}, {"antiresonances_hz", f.antiresonances_hz}};
}

void run_mode_shape(Context& ctx, const ModeShapeArgs& a) {
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
  if (ctx.json) {
    print_json(j);
  } else {
    std::printf(
        "Seed Appendix D, Table D.1 on the default tube: (a) mode-shape CMCM (%s%s%s), "
        "(b) extended CMCM from frequencies, (c) output-error fit of a simulated capture "
        "(noise %.3g)\n\n",
        update::to_string(s.shapes.staging), a.linearise ? ", D.10 linearised" : "",
        a.diagonal ? ", i = j pairs" : "", a.capture_noise);
    std::printf("%s\n", update::to_markdown(s).c_str());
    std::printf("(a) %s; epsT33 for D.11 by eq. 201: %.2f eps0\n",
                s.shapes.ok ? "ok" : s.shapes.message.c_str(), s.eps_t33_eq201 / model::kEps0);
    for (const auto& eq : s.shapes.systems) {
      std::printf("    %lld equations, rank %d, singular values",
                  static_cast<long long>(eq.g.rows()), eq.rank);
      for (Eigen::Index k = 0; k < eq.singular_values.size(); ++k)
        std::printf(" %.3g", eq.singular_values[k]);
      std::printf("\n");
    }
    std::printf("(b) %s %s\n(c) %s %s (chi2/dof %.4g%s)\n", update::to_string(s.cmcm.status),
                s.cmcm.message.c_str(), update::to_string(s.output_error.status),
                s.output_error.message.c_str(), s.output_error.chi2_per_dof,
                s.output_error.lack_of_fit ? ", lack of fit" : "");
  }
  if (!s.shapes.ok) ctx.exit_code = kInternal;
}

}  // namespace

void register_mode_shape_command(CLI::App* model, Context& ctx) {
  auto args = std::make_shared<ModeShapeArgs>();
  auto* cmd = model->add_subcommand(
      "mode-shape-cmcm",
      "Seed Appendix D: Table D.1 by mode-shape CMCM, extended CMCM and output error");
  cmd->add_option("--capture-noise", args->capture_noise,
                  "Noise of (c)'s simulated capture, std(noise)/std(clean) per channel")
      ->capture_default_str();
  cmd->add_option("--seed", args->seed, "Noise seed")->capture_default_str();
  cmd->add_option("--staging", args->staging, "joint (all eleven unknowns) or seed (D.1 then D.2)")
      ->capture_default_str();
  cmd->add_flag("--linearise-cross-terms", args->linearise, "The seed's linearised D.10 (biased)");
  cmd->add_flag("--diagonal-pairs", args->diagonal, "Only the i = j mode pairs");
  add_json_flag(cmd, ctx);
  cmd->callback(
      [&ctx, args] { ctx.exit_code = run_command(ctx, [&] { run_mode_shape(ctx, *args); }); });
}

}  // namespace piezo::cli
