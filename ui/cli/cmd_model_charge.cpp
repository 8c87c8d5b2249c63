// `piezobench model charge`: the seed's §5.1 simulation study on our FE tube
// (Figs 24–29: the charge of a 500·e^{−0.001 t} V drive, Prony-SS with the
// seed's order rule and ours, the FFT ratio and the averaged cross spectra
// against the stepped-harmonic |Z|). A thin shell (the CLI's room, ui/cli):
// the work is jobs/charge_study_job.hpp.
//   model charge [--noise L] [--rayleigh-beta S] [--samples N,N] [--hankel H]
//                [--records R] [--seed K] [--csv FILE] [--plot-dir DIR] [--plot-format svg|png] [--json]
// Exit codes: 0 ok, 1 the study failed, 2 bad input.
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

#include "jobs/charge_study_job.hpp"
#include "ui/cli/cli_common.hpp"

namespace piezo::cli {

namespace {

std::string percent_list(const nlohmann::json& a) {
  std::string s;
  char b[32];
  for (const auto& e : a) {
    if (e.is_number())
      std::snprintf(b, sizeof b, "%s%+.3f", s.empty() ? "" : " ", 100 * e.get<double>());
    else
      std::snprintf(b, sizeof b, "%s%s", s.empty() ? "" : " ", "missing");
    s += b;
  }
  return s;
}

void print_charge(const nlohmann::json& j) {
  std::printf("%s; %s tube, %d modes + residual; drive %g·e^(%g t) V, %g MS/s, %d samples; Rayleigh β %g s\n",
              j["experiment"].get<std::string>().c_str(), j["material"].get<std::string>().c_str(),
              j["modes"].get<int>(), j["drive"]["amplitude_v"].get<double>(), j["drive"]["pole_per_s"].get<double>(),
              1e-6 * j["sample_rate_hz"].get<double>(), j["record_samples"].get<int>(),
              j["rayleigh_beta_s"].get<double>());
  const auto& n = j["noise"];
  std::printf("charge: max |q| %.4g µC, std %.4g µC; noise σ %.4g C (%g of std)%s\n",
              1e6 * j["charge"]["max_abs_c"].get<double>(), 1e6 * j["charge"]["std_c"].get<double>(),
              n["charge_sigma_c"].get<double>(), n["level"].get<double>(),
              n["records"].get<int>() > 1 ? (", " + std::to_string(n["records"].get<int>()) + " records, seed " +
                                             std::to_string(n["seed"].get<int>()))
                                                .c_str()
                                          : "");
  std::printf("true |Z| extrema (harmonic):");
  for (const auto& f : j["truth"]["resonances_hz"]) std::printf(" min %.1f", f.get<double>());
  for (const auto& f : j["truth"]["antiresonances_hz"]) std::printf(" max %.1f", f.get<double>());
  std::printf(" Hz\n|Z| error away from the peaks (±1.5 %%), 1–120 kHz, and the extrema's errors [%%]:\n");
  std::printf("  %-52s %9s %9s %9s   %s | %s\n", "estimate", "median dB", "max dB", "at kHz", "minima", "maxima");
  for (const auto& e : j["estimates"])
    std::printf("  %-52s %9.3g %9.3g %9.1f   %s | %s\n", e["label"].get<std::string>().c_str(),
                e["median_db"].get<double>(), e["max_db"].get<double>(), 1e-3 * e["max_db_at_hz"].get<double>(),
                percent_list(e["resonance_err_rel"]).c_str(), percent_list(e["antiresonance_err_rel"]).c_str());
  if (j.contains("singular_values")) {
    const auto& s = j["singular_values"];
    std::printf("seed rule (%d samples, %d x %d Hankel): largest drop s_%d/s_%d = %.3g", s["samples"].get<int>(),
                s["hankel"].get<int>(), s["hankel"].get<int>(), s["largest_drop_order"].get<int>(),
                s["largest_drop_order"].get<int>() + 1, s["largest_drop_ratio"].get<double>());
    if (s.contains("s26_over_s27")) std::printf("; s_26/s_27 = %.4g (the seed's gap)", s["s26_over_s27"].get<double>());
    std::printf("\n");
  }
  if (j.contains("plots"))
    for (const auto& f : j["plots"]) std::printf("wrote %s\n", f.get<std::string>().c_str());
  if (j.contains("csv")) std::printf("wrote %s\n", j["csv"].get<std::string>().c_str());
}

}  // namespace

void register_model_charge_command(CLI::App* model, Context& ctx,
                                   const std::function<void(CLI::App*, jobs::ModelRequest&)>& add_model_options) {
  auto a = std::make_shared<jobs::ChargeStudyRequest>();
  auto* c = model->add_subcommand(
      "charge", "Seed 5.1 (Figs 24-29): |Z| from the tube's charge by Prony-SS, FFT and cross spectra");
  add_model_options(c, a->model);
  c->add_option("--noise", a->noise, "White noise on the charge as sigma_n/sigma_s (0: seed 5.1.1; 0.1: 5.1.2)")
      ->capture_default_str();
  c->add_option("--rayleigh-beta", a->beta_s, "Rayleigh beta [s] (default: 0 without noise, 1e-7 with, the seed's)");
  c->add_option("--samples", a->samples, "Prony-SS and the FFT on the first N samples (the seed: 1000,3000)")
      ->delimiter(',')
      ->capture_default_str();
  c->add_option("--hankel", a->hankel, "Rows = columns of the seed rule's Hankel matrix (capped at N/2)")
      ->capture_default_str();
  c->add_option("--records", a->records, "Noisy records for the averaged cross spectra")->capture_default_str();
  c->add_option("--seed", a->seed, "Noise draw")->capture_default_str();
  c->add_option("--modes", a->modes, "Short-circuit modes of the port model")->capture_default_str();
  c->add_option("--csv", a->csv, "|Z| of the truth and of every estimate on the 200 Hz grid (a CSV file)");
  c->add_option("--plot-dir", a->plot_dir,
                "Write charge-signals, charge-impedance and charge-singular-values here (Figs 24-29)");
  c->add_option("--plot-format", a->plot_format, "svg or png")->capture_default_str();
  add_json_flag(c, ctx);
  c->callback([&ctx, a] {
    ctx.exit_code = run_command(ctx, [&] {
      const auto j = jobs::run_charge_study(*a);
      if (ctx.json)
        print_json(j);
      else
        print_charge(j);
    });
  });
}

}  // namespace piezo::cli
