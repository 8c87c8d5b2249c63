// `piezobench model bar`: the seed's Appendix A bar vibrators (33 and 31 mode,
// free-free or fixed at one end with a mass at the other). A thin shell (the
// CLI's room, ui/cli): the work is jobs/model_bar_job.hpp.
//   model bar [--mode 31|33] [--ends free-free|fixed-mass] [--material M]
//             [--length M] [--width M] [--thickness M] [--end-mass KG] [--fmax HZ] [--json]
// Exit codes: 0 ok, 2 bad input.
#include <cstdio>
#include <memory>
#include <string>

#include "jobs/model_bar_job.hpp"
#include "ui/cli/cli_common.hpp"

namespace piezo::cli {

namespace {

void print_bar(const nlohmann::json& j) {
  const auto& g = j["geometry"];
  std::printf("%s-mode bar, %s, %s: L %g mm, w %g mm, h %g mm (%.4g g", j["mode"].get<std::string>().c_str(),
              j["ends"].get<std::string>().c_str(), j["material"].get<std::string>().c_str(),
              1e3 * g["length_m"].get<double>(), 1e3 * g["width_m"].get<double>(),
              1e3 * g["thickness_m"].get<double>(), 1e3 * g["bar_mass_kg"].get<double>());
  if (g["end_mass_kg"].get<double>() > 0) std::printf(", end mass %.4g g", 1e3 * g["end_mass_kg"].get<double>());
  std::printf(")\n");
  std::printf("k%s of the material %.4f; the wave runs on %s, %.1f m/s; C free %.4g F, clamped %.4g F\n",
              j["mode"].get<std::string>().c_str(), j["k_material"].get<double>(),
              j["wave_compliance"].get<std::string>().c_str(), j["wave_speed_m_s"].get<double>(),
              j["c_free_f"].get<double>(), j["c_clamped_f"].get<double>());
  std::printf("      fr [Hz]        fa [Hz]    k_eff   (below %.0f Hz)\n", j["fmax_hz"].get<double>());
  for (const auto& p : j["pairs"]) {
    if (p["antiresonance_hz"].is_number())
      std::printf("  %12.2f   %12.2f   %.4f\n", p["resonance_hz"].get<double>(), p["antiresonance_hz"].get<double>(),
                  p["k_eff"].get<double>());
    else
      std::printf("  %12.2f   (none below the limit)\n", p["resonance_hz"].get<double>());
  }
  if (j.contains("ieee176_k"))
    std::printf("IEEE Std 176 reads k%s = %.6f back from the first pair\n", j["mode"].get<std::string>().c_str(),
                j["ieee176_k"].get<double>());
}

}  // namespace

void register_model_bar_command(CLI::App* model, Context& ctx) {
  auto a = std::make_shared<jobs::BarRequest>();
  auto* bar = model->add_subcommand("bar", "Seed Appendix A: the 33- and 31-mode bar vibrators (eqs A.1-A.8)");
  bar->add_option("--mode", a->mode, "33 (poled and driven along the length) or 31 (across it)")
      ->capture_default_str();
  bar->add_option("--ends", a->ends, "free-free, or fixed-mass (fixed at one end, --end-mass at the other)")
      ->capture_default_str();
  bar->add_option("--material", a->material, "Material preset (see `model materials`); its density is used")
      ->capture_default_str();
  bar->add_option("--length", a->length_m, "Bar length L [m]")->capture_default_str();
  bar->add_option("--width", a->width_m, "Width w [m]")->capture_default_str();
  bar->add_option("--thickness", a->thickness_m, "Thickness h [m] (31: between the electrodes)")
      ->capture_default_str();
  bar->add_option("--end-mass", a->end_mass_kg, "Mass at the free end [kg] (fixed-mass; 0: fixed-free)")
      ->capture_default_str();
  bar->add_option("--fmax", a->fmax_hz, "List the pairs up to this frequency [Hz] (0: four times c/(2L))")
      ->capture_default_str();
  add_json_flag(bar, ctx);
  bar->callback([&ctx, a] {
    ctx.exit_code = run_command(ctx, [&] {
      const auto j = jobs::run_bar(*a);
      if (ctx.json)
        print_json(j);
      else
        print_bar(j);
    });
  });
}

}  // namespace piezo::cli
