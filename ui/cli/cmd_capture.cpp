// `piezobench capture info FILE [--json]`: the set-up and, per shot, N, rate,
// excitation, min/max/RMS of v1 and v2 and a clipping flag.
#include <cstdio>
#include <iostream>

#include "acquisition/capture_file.hpp"
#include "acquisition/contained_read.hpp"
#include "dsp/signal_stats.hpp"
#include "ui/cli/cli_common.hpp"

namespace piezo::cli {

namespace {

template <class T>
void put(nlohmann::json& j, const char* key, const std::optional<T>& v) {
  if (v) j[key] = *v;
}

nlohmann::json stats_json(const dsp::SignalStats& s) {
  return {{"min_v", s.min}, {"max_v", s.max}, {"rms_v", s.rms}, {"clipped", s.clipped}};
}

nlohmann::json capture_info_json(const acq::Capture& cap) {
  nlohmann::json j;
  j["file"] = cap.path;
  j["format"] = std::string(acq::kFormatName);
  j["format_version"] = acq::kFormatVersion;
  put(j, "created_utc", cap.created_utc);
  put(j, "software", cap.software);
  nlohmann::json s;
  const auto& st = cap.setup;
  s["divider_r1_ohm"] = st.divider_r1_ohm;
  put(s, "transducer_id", st.transducer_id);
  put(s, "material", st.material);
  put(s, "notes", st.notes);
  auto g = st.geometry();
  s["inner_diameter_m"] = g.inner_diameter_m;
  s["outer_diameter_m"] = g.outer_diameter_m;
  s["length_m"] = g.length_m;
  s["density_kg_m3"] = g.density_kg_m3;
  s["geometry_defaults_applied"] =
      !(st.inner_diameter_m && st.outer_diameter_m && st.length_m && st.density_kg_m3);
  j["setup"] = s;
  j["shots"] = nlohmann::json::array();
  for (const auto& sh : cap.shots) {
    dsp::ClipDetection clip1, clip2;
    clip1.range_v = sh.range_v(1);
    clip2.range_v = sh.range_v(2);
    auto s1 = dsp::compute_stats(sh.v1, clip1);
    auto s2 = dsp::compute_stats(sh.v2, clip2);
    nlohmann::json o;
    o["name"] = sh.name;
    o["samples"] = sh.samples();
    o["sample_rate_hz"] = sh.sample_rate_hz;
    o["duration_s"] = sh.samples() / sh.sample_rate_hz;
    o["excitation"] = std::string(acq::to_string(sh.excitation));
    o["role"] = std::string(acq::to_string(sh.role));
    o["pretrigger_samples"] = sh.pretrigger_samples;
    put(o, "amplitude_v", sh.amplitude_v);
    put(o, "decay_per_s", sh.decay_per_s);
    put(o, "frequency_hz", sh.frequency_hz);
    put(o, "f_start_hz", sh.f_start_hz);
    put(o, "f_stop_hz", sh.f_stop_hz);
    put(o, "load_ohm", sh.load_ohm);
    put(o, "load_parallel_f", sh.load_parallel_f);
    put(o, "daq_range_v", sh.daq_range_v);
    put(o, "v1_range_v", sh.v1_range_v);
    put(o, "v2_range_v", sh.v2_range_v);
    if (sh.adc_bits) o["adc_bits"] = *sh.adc_bits;
    o["v1"] = stats_json(s1);
    o["v2"] = stats_json(s2);
    o["clipped"] = s1.clipped || s2.clipped;
    j["shots"].push_back(o);
  }
  return j;
}

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

void register_capture_commands(CLI::App& app, Context& ctx) {
  auto* capture = app.add_subcommand("capture", "Inspect piezo-capture/1 files");
  capture->require_subcommand(1);
  auto* info = capture->add_subcommand("info", "Set-up and per-shot summary of a capture");
  auto file = std::make_shared<std::string>();
  info->add_option("FILE", *file, "Capture file (.h5)")->required();
  add_json_flag(info, ctx);
  add_json_flag(capture, ctx);
  info->callback([&ctx, file] {
    ctx.exit_code = run_command(ctx, [&] {
      auto cap = acq::read_capture_contained(*file);  // a crash of libhdf5 costs the file only
      auto j = capture_info_json(cap);
      if (ctx.json)
        print_json(j);
      else
        print_text(j);
    });
  });
}

}  // namespace piezo::cli
