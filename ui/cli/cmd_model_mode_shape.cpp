// `piezobench model mode-shape-cmcm`: seed Appendix D's numerical study
// (Table D.1) on the default tube — mode-shape CMCM beside the extended CMCM
// and the output-error fit (update/appendix_d_study.hpp). A thin shell (the
// CLI's room, ui/cli): the study runs in jobs/mode_shape_job.hpp.
//   model mode-shape-cmcm [--capture-noise R] [--seed N] [--staging joint|seed]
//                         [--linearise-cross-terms] [--diagonal-pairs] [--json]
// Exit codes: 0 ok, 2 bad input, 1 when the mode-shape update fails.
#include <cstdio>

#include "jobs/mode_shape_job.hpp"
#include "ui/cli/cli_common.hpp"

namespace piezo::cli {

namespace {

void run_mode_shape(Context& ctx, const jobs::ModeShapeRequest& a) {
  const auto r = jobs::run_mode_shape(a);
  const auto& s = r.study;
  const auto& j = r.json;
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
  auto args = std::make_shared<jobs::ModeShapeRequest>();
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
