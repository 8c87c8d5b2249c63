// `piezobench capture info FILE [--json]`: the set-up and, per shot, N, rate,
// excitation, min/max/RMS of v1 and v2 and a clipping flag. The CLI's room
// (ui/cli): the summary is jobs/capture_info_job.hpp.
#include <cstdio>
#include <iostream>

#include "jobs/capture_info_job.hpp"
#include "ui/cli/cli_common.hpp"

namespace piezo::cli {

namespace {

void print_text(const nlohmann::json& j) {
  std::printf("%s\n", j["file"].get<std::string>().c_str());
  std::printf("  format          piezo-capture/%d\n", j["format_version"].get<int>());
  if (j.contains("software"))
    std::printf("  software        %s\n", j["software"].get<std::string>().c_str());
  if (j.contains("created_utc"))
    std::printf("  created_utc     %s\n", j["created_utc"].get<std::string>().c_str());
  const auto& s = j["setup"];
  std::printf("  R1              %.6g ohm\n", s["divider_r1_ohm"].get<double>());
  if (s.contains("transducer_id"))
    std::printf("  transducer      %s\n", s["transducer_id"].get<std::string>().c_str());
  if (s.contains("material"))
    std::printf("  material        %s\n", s["material"].get<std::string>().c_str());
  std::printf("  tube            Di %.4g mm, Do %.4g mm, L %.4g mm, rho %.5g kg/m3%s\n",
              s["inner_diameter_m"].get<double>() * 1e3, s["outer_diameter_m"].get<double>() * 1e3,
              s["length_m"].get<double>() * 1e3, s["density_kg_m3"].get<double>(),
              s["geometry_defaults_applied"].get<bool>() ? " (defaults applied)" : "");
  std::printf("\n  %-6s %-5s %-9s %8s %10s  %-30s %-30s %s\n", "shot", "role", "excitation", "N",
              "rate", "v1 min/max/rms [V]", "v2 min/max/rms [V]", "clipped");
  for (const auto& o : j["shots"]) {
    auto col = [](const nlohmann::json& c) {
      char buf[64];
      std::snprintf(buf, sizeof buf, "%+.4g/%+.4g/%.4g", c["min_v"].get<double>(),
                    c["max_v"].get<double>(), c["rms_v"].get<double>());
      return std::string(buf);
    };
    std::printf("  %-6s %-5s %-9s %8zu %8.4gHz  %-30s %-30s %s\n",
                o["name"].get<std::string>().c_str(), o["role"].get<std::string>().c_str(),
                o["excitation"].get<std::string>().c_str(), o["samples"].get<std::size_t>(),
                o["sample_rate_hz"].get<double>(), col(o["v1"]).c_str(), col(o["v2"]).c_str(),
                o["clipped"].get<bool>() ? "CLIPPED" : "no");
  }
}

}  // namespace

void register_capture_command(CLI::App& app, Context& ctx) {
  auto* capture = app.add_subcommand("capture", "Inspect piezo-capture/1 files");
  capture->require_subcommand(1);
  auto* info = capture->add_subcommand("info", "Set-up and per-shot summary of a capture");
  auto file = std::make_shared<std::string>();
  info->add_option("FILE", *file, "Capture file (.h5)")->required();
  add_json_flag(info, ctx);
  add_json_flag(capture, ctx);
  info->callback([&ctx, file] {
    ctx.exit_code = run_command(ctx, [&] {
      auto j = jobs::capture_info(*file);
      if (ctx.json)
        print_json(j);
      else
        print_text(j);
    });
  });
}

}  // namespace piezo::cli
