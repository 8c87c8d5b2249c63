// `piezobench model three-d` and `model constrained`: the seed's 3-D model
// (Table 3's 3-D column, Fig 17) and its constrained FE (Fig 19). A thin
// shell (the CLI's room, ui/cli): the work is jobs/model_3d_job.hpp.
//   model three-d     [tube options] [--fmax HZ] [--max-n N] [--step HZ] [--rayleigh-beta S]
//                     [--csv] [--plot OUT.png|.svg] [--json]
//   model constrained [tube options] [--fmin HZ] [--fmax HZ] [--step HZ] [--rayleigh-beta S]
//                     [--csv] [--plot OUT.png|.svg] [--json]
// --csv prints the |Z| curves (Fig 17: two_d, three_d; Fig 19: free_fe,
// constrained_fe, ring) instead of the summary. Exit codes: 0 ok, 2 bad
// input, 1 when a solve fails.
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>

#include "jobs/model_3d_job.hpp"
#include "ui/cli/cli_common.hpp"

namespace piezo::cli {

namespace {

struct ThreeDArgs {
  jobs::ThreeDRequest req;
  bool csv = false;
  std::string plot;
};

struct ConstrainedArgs {
  jobs::ConstrainedRequest req;
  bool csv = false;
  std::string plot;
};

// --json prints the JSON, --csv the curves; true when one of them did.
bool printed_as_data(const Context& ctx, const nlohmann::json& j, const jobs::ImpedanceCurves& c, bool csv) {
  if (ctx.json)
    print_json(j);
  else if (csv)
    jobs::write_curves_csv(std::cout, c);
  return ctx.json || csv;
}

void print_three_d(const ThreeDArgs& a, const nlohmann::json& j) {
  std::printf("%s (%s class), mesh %d x %d: the 3-D tube by circumferential harmonics n = 0..%d\n",
              a.req.model.material.c_str(), j["model_class"].get<std::string>().c_str(), a.req.model.n_radial,
              a.req.model.n_axial, j["highest_harmonic"].get<int>());
  std::printf("Table 3 (electrically active modes)   2-D [Hz]      3-D [Hz]   3-D/2-D - 1\n");
  for (const auto& row : j["table3"])
    std::printf("  %-5s %zu %29.2f %13.2f %12.2e\n", row["circuit"].get<std::string>().c_str(),
                row["mode"].get<std::size_t>(), row["two_d_hz"].get<double>(), row["three_d_hz"].get<double>(),
                row["relative_difference"].get<double>());
  std::printf("torsion, FE against exact k/(2L) sqrt(cE66/rho):");
  for (const auto& t : j["torsion_check"])
    std::printf("  %.2f / %.2f Hz", t["fe_hz"].get<double>(), t["exact_hz"].get<double>());
  std::printf("\nmodes below %.0f Hz (n >= 1: each a pair; * = electrically active):\n", j["fmax_hz"].get<double>());
  for (const auto& h : j["harmonics"]) {
    std::printf("  n=%d %s:", h["n"].get<int>(), h["family"].get<std::string>().c_str());
    for (const auto& m : h["modes"])
      std::printf(" %.0f%s", m["frequency_hz"].get<double>(), m["electrically_active"].get<bool>() ? "*" : "");
    std::printf("\n");
  }
  const auto& c = j["counts_below_fmax"];
  const auto& d = j["fig17"]["three_d_vs_two_d"];
  std::printf("below %.0f Hz: %d charged axisymmetric, %d torsional, %d non-axisymmetric pairs (no charge)\n",
              j["fmax_hz"].get<double>(), c["axisymmetric_charged"].get<int>(), c["torsional"].get<int>(),
              c["non_axisymmetric_pairs"].get<int>());
  if (d["max_abs_db"].is_number())
    std::printf("Fig 17: |Z| 3-D against 2-D, %g..%g Hz: max %.3g dB (at %.0f Hz), median %.3g dB\n",
                j["fig17"]["fmin_hz"].get<double>(), j["fig17"]["fmax_hz"].get<double>(),
                d["max_abs_db"].get<double>(), d["max_at_hz"].get<double>(), d["median_abs_db"].get<double>());
}

// A --plot name the writer will take, checked before the work.
void check_plot_name(const std::string& plot) {
  if (plot.empty()) return;
  const std::string ext = std::filesystem::path(plot).extension().string();
  if (ext != ".png" && ext != ".svg") throw InputError("--plot " + plot + ": give a .png or .svg file name");
}

void run_three_d(Context& ctx, const ThreeDArgs& a) {
  check_plot_name(a.plot);
  ProgressBar bar("three-d", !ctx.json && !a.csv);
  const auto r = jobs::run_three_d(a.req, [&](int done, int total) {
    bar.update(total > 0 ? static_cast<double>(done) / total : 0.0, "harmonic " + std::to_string(done - 1));
  });
  bar.finish();
  const auto& j = r.json;
  if (!printed_as_data(ctx, j, r.fig17, a.csv)) print_three_d(a, j);
  // The plot after the numbers: a plot that cannot be written loses none of them.
  if (!a.plot.empty()) {
    char sub[160];
    std::snprintf(sub, sizeof sub, "%s, Rayleigh beta %g s; 3-D = harmonic 0 (n >= 1 carry no charge)",
                  a.req.model.material.c_str(), a.req.beta);
    jobs::write_curves_plot(r.fig17, "Fig 17: |Z| of the 2-D and 3-D models", sub, a.plot);
  }
}

void print_list(const char* name, const nlohmann::json& v) {
  std::printf("  %-16s", name);
  for (const auto& f : v) std::printf(" %.1f", f.get<double>());
  std::printf("\n");
}

void print_constrained(const ConstrainedArgs& a, const nlohmann::json& j) {
  std::printf("%s (%s class), mesh %d x %d: electrically active modes below %.0f Hz [Hz]\n",
              a.req.model.material.c_str(), j["model_class"].get<std::string>().c_str(), a.req.model.n_radial,
              a.req.model.n_axial, j["grid"]["fmax_hz"].get<double>());
  print_list("free, short", j["free_fe"]["short_circuit_hz"]);
  print_list("free, open", j["free_fe"]["open_circuit_hz"]);
  print_list("u_z = 0, short", j["constrained_fe"]["short_circuit_hz"]);
  print_list("u_z = 0, open", j["constrained_fe"]["open_circuit_hz"]);
  std::printf("  ring (eq 42/43)  %.1f / %.1f (k31 %.4f)\n", j["ring"]["resonance_hz"].get<double>(),
              j["ring"]["antiresonance_hz"].get<double>(), j["ring"]["k31"].get<double>());
  for (const char* k : {"free_vs_ring", "constrained_vs_ring"}) {
    const auto& d = j[k];
    if (d["max_abs_db"].is_number())
      std::printf("|Z| %s: median %.3g dB, max %.3g dB at %.0f Hz\n", k, d["median_abs_db"].get<double>(),
                  d["max_abs_db"].get<double>(), d["max_at_hz"].get<double>());
  }
}

void run_constrained(Context& ctx, const ConstrainedArgs& a) {
  check_plot_name(a.plot);
  const auto r = jobs::run_constrained(a.req);
  const auto& j = r.json;
  if (!printed_as_data(ctx, j, r.fig19, a.csv)) print_constrained(a, j);
  if (!a.plot.empty())
    jobs::write_curves_plot(r.fig19, "Fig 19: constrained FE (u_z = 0) against the analytic ring",
                            a.req.model.material + ", free FE beside them", a.plot);
}

}  // namespace

void register_model_3d_commands(CLI::App* model, Context& ctx,
                                const std::function<void(CLI::App*, jobs::ModelRequest&)>& add_model_options) {
  auto t = std::make_shared<ThreeDArgs>();
  auto* three = model->add_subcommand(
      "three-d", "Seed Table 3 (3-D column) and Fig 17: the 3-D tube by circumferential harmonics");
  add_model_options(three, t->req.model);
  three->add_option("--fmax", t->req.fmax_hz, "List modes up to this frequency; Fig 17's last point [Hz]")
      ->capture_default_str();
  three->add_option("--max-n", t->req.max_n, "Highest harmonic (0: until one has no mode below --fmax)")
      ->capture_default_str();
  three->add_option("--step", t->req.step_hz, "Fig 17's frequency step [Hz]")->capture_default_str();
  three->add_option("--rayleigh-beta", t->req.beta, "Fig 17's Rayleigh beta [s]")->capture_default_str();
  three->add_flag("--csv", t->csv, "Fig 17's curves: f_hz,two_d_abs_ohm,three_d_abs_ohm");
  three->add_option("--plot", t->plot, "Fig 17 as PNG or SVG (by the extension)");
  add_json_flag(three, ctx);
  three->callback([&ctx, t] { ctx.exit_code = run_command(ctx, [&] { run_three_d(ctx, *t); }); });

  auto c = std::make_shared<ConstrainedArgs>();
  auto* con = model->add_subcommand(
      "constrained", "Seed Fig 19: the FE with axial motion constrained, the free FE and the analytic ring");
  add_model_options(con, c->req.model);
  con->add_option("--fmin", c->req.fmin_hz, "First frequency [Hz]")->capture_default_str();
  con->add_option("--fmax", c->req.fmax_hz, "Last frequency [Hz]")->capture_default_str();
  con->add_option("--step", c->req.step_hz, "Frequency step [Hz]")->capture_default_str();
  con->add_option("--rayleigh-beta", c->req.beta, "Rayleigh beta [s] of both FE curves")->capture_default_str();
  con->add_flag("--csv", c->csv, "The curves: f_hz,free_fe_abs_ohm,constrained_fe_abs_ohm,ring_abs_ohm");
  con->add_option("--plot", c->plot, "Fig 19 as PNG or SVG (by the extension)");
  add_json_flag(con, ctx);
  con->callback([&ctx, c] { ctx.exit_code = run_command(ctx, [&] { run_constrained(ctx, *c); }); });
}

}  // namespace piezo::cli
