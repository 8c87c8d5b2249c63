// The jobs' room (jobs/): a capture's summary (see capture_info_job.hpp).
#include "jobs/capture_info_job.hpp"

#include <optional>

#include "acquisition/capture_file.hpp"
#include "acquisition/contained_read.hpp"
#include "dsp/signal_stats.hpp"

namespace piezo::jobs {

namespace {

template <class T>
void put(nlohmann::json& j, const char* key, const std::optional<T>& v) {
  if (v) j[key] = *v;
}

nlohmann::json stats_json(const dsp::SignalStats& s) {
  return {{"min_v", s.min}, {"max_v", s.max}, {"rms_v", s.rms}, {"clipped", s.clipped}};
}

}  // namespace

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

nlohmann::json capture_info(const std::string& path) {
  auto cap = acq::read_capture_contained(path);  // a crash of libhdf5 costs the file only
  return capture_info_json(cap);
}

}  // namespace piezo::jobs
