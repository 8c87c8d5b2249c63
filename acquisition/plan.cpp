#include "acquisition/plan.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <optional>
#include <random>
#include <sstream>
#include <stdexcept>
#include <toml++/toml.h>

#include "model/seed_circuit.hpp"

namespace piezo::acq {

namespace {
void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("measurement plan: " + what);
}
}  // namespace

void MeasurementPlan::validate() const {
  const auto& e = excitation;
  // Every number finite: each ends up in an instrument command or a capture
  // attribute, and the capture reader refuses non-finite attributes.
  for (auto [name, v] : {std::pair{"sample_rate_hz", sample_rate_hz}, std::pair{"range_v", range_v},
                         std::pair{"r1_ohm", setup.divider_r1_ohm}, std::pair{"amplitude_v", e.amplitude_v},
                         std::pair{"decay_per_s", e.decay_per_s}, std::pair{"frequency_hz", e.frequency_hz},
                         std::pair{"f_start_hz", e.f_start_hz}, std::pair{"f_stop_hz", e.f_stop_hz},
                         std::pair{"f_step_hz", e.f_step_hz}, std::pair{"burst_fraction", e.burst_fraction}})
    require(std::isfinite(v), std::string(name) + " must be a finite number");
  require(sample_rate_hz > 0, "sample_rate_hz must be positive");
  require(samples >= kMinSamples, "samples must be at least 16");
  require(samples <= kMaxSamples, "samples must be at most " + std::to_string(kMaxSamples));
  require(pretrigger_samples < samples, "pretrigger_samples must be below samples");
  require(shots >= 1 && shots <= kMaxShots, "shots must be in [1, " + std::to_string(kMaxShots) + "]");
  require(setup.divider_r1_ohm > 0, "r1_ohm must be positive");
  for (auto [name, v] : {std::pair{"inner_diameter_m", setup.inner_diameter_m},
                         std::pair{"outer_diameter_m", setup.outer_diameter_m},
                         std::pair{"length_m", setup.length_m}, std::pair{"density_kg_m3", setup.density_kg_m3}})
    require(!v || (std::isfinite(*v) && *v > 0), std::string(name) + " must be positive and finite");
  require(e.amplitude_v > 0 && e.amplitude_v <= 10, "amplitude_v must be in (0, 10] V");
  if (e.kind == Excitation::ExpDecay) require(e.decay_per_s > 0, "decay_per_s must be positive");
  const double nyq = 0.5 * sample_rate_hz;
  std::size_t n_steps = 1;
  if (e.kind == Excitation::Sine) {
    require(e.frequency_hz > 0 && e.frequency_hz < nyq, "frequency_hz must be in (0, rate/2)");
    if (e.f_step_hz > 0) {
      require(e.f_start_hz > 0 && e.f_stop_hz >= e.f_start_hz && e.f_stop_hz < nyq,
              "stepped sine needs 0 < f_start_hz <= f_stop_hz < rate/2");
      // Counted before steps() builds them: a tiny step must not loop for ever.
      const double n = std::floor((e.f_stop_hz * (1 + 1e-12) - e.f_start_hz) / e.f_step_hz) + 1;
      require(n <= static_cast<double>(kMaxSteps),
              "stepped sine: f_step_hz gives more than " + std::to_string(kMaxSteps) + " steps");
      n_steps = static_cast<std::size_t>(n);
    }
  }
  require(n_steps * static_cast<std::size_t>(shots) <= static_cast<std::size_t>(kMaxShots),
          "steps x shots must be at most " + std::to_string(kMaxShots));
  if (e.kind == Excitation::Chirp)
    require(e.f_start_hz > 0 && e.f_stop_hz > e.f_start_hz && e.f_stop_hz < nyq,
            "chirp needs 0 < f_start_hz < f_stop_hz < rate/2");
  require(e.burst_fraction > 0 && e.burst_fraction <= 1, "burst_fraction must be in (0, 1]");
  if (e.kind == Excitation::Chirp || e.kind == Excitation::Noise)
    require(std::llround(e.burst_fraction * static_cast<double>(samples - pretrigger_samples)) >= 2,
            "burst_fraction x post-trigger samples must be at least 2 samples");
  require(range_v >= 0, "range_v must be >= 0");
}

double MeasurementPlan::daq_range_v() const {
  return range_v > 0 ? range_v : 1.25 * excitation.amplitude_v;
}

std::vector<ExcitationSpec> MeasurementPlan::steps() const {
  const auto& e = excitation;
  if (e.kind != Excitation::Sine || e.f_step_hz <= 0) return {e};
  std::vector<ExcitationSpec> out;
  for (double f = e.f_start_hz; f <= e.f_stop_hz * (1 + 1e-12); f += e.f_step_hz) {
    ExcitationSpec s = e;
    s.frequency_hz = f;
    out.push_back(s);
  }
  return out;
}

std::vector<double> synthesize(const ExcitationSpec& e, double fs, std::size_t n) {
  std::vector<double> w(n);
  const std::size_t nb = e.kind == Excitation::Chirp || e.kind == Excitation::Noise
                             ? static_cast<std::size_t>(std::llround(e.burst_fraction * static_cast<double>(n)))
                             : n;
  const double T = static_cast<double>(nb) / fs;
  switch (e.kind) {
    case Excitation::ExpDecay:
      for (std::size_t k = 0; k < n; ++k) w[k] = std::exp(-e.decay_per_s * k / fs);
      break;
    case Excitation::Sine:
      for (std::size_t k = 0; k < n; ++k) w[k] = std::sin(2 * M_PI * e.frequency_hz * k / fs);
      break;
    case Excitation::Chirp: {  // linear sweep over the record
      const double rate = (e.f_stop_hz - e.f_start_hz) / T;
      for (std::size_t k = 0; k < nb; ++k) {
        double t = k / fs;
        w[k] = std::sin(2 * M_PI * (e.f_start_hz * t + 0.5 * rate * t * t));
      }
      break;
    }
    case Excitation::Noise: {
      std::mt19937_64 rng(e.noise_seed);
      std::normal_distribution<double> g(0.0, 1.0);
      double peak = 0;
      for (std::size_t k = 0; k < nb; ++k) {
        w[k] = g(rng);
        peak = std::max(peak, std::fabs(w[k]));
      }
      if (peak > 0)
        for (auto& x : w) x /= peak;
      break;
    }
    case Excitation::Arbitrary:
      throw std::invalid_argument("synthesize: arbitrary excitation has no formula");
  }
  return w;
}

MeasurementPlan load_plan_toml(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::invalid_argument("plan " + file.string() + ": cannot open the file");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw std::invalid_argument("plan " + file.string() + ": cannot read the file");
  return parse_plan_toml(text.str(), file.string());
}

MeasurementPlan parse_plan_toml(std::string_view toml_text, const std::string& source) {
  toml::table t;
  try {
    t = toml::parse(toml_text, source);
  } catch (const toml::parse_error& e) {
    throw std::invalid_argument("plan " + source + ": " + std::string(e.description()) +
                                " at line " + std::to_string(e.source().begin.line));
  }
  MeasurementPlan p;
  auto fail = [&](const std::string& key, const std::string& why) {
    throw std::invalid_argument("plan " + source + ": " + key + ": " + why);
  };
  // A key of the wrong type is an error, as an unknown key is: a default
  // must not silently stand in for what the file says.
  auto num = [&](const toml::table& tb, const char* key, double& out, const std::string& where) {
    if (auto n = tb.get(key)) {
      if (auto v = n->value<double>()) out = *v;
      else fail(where + key, "expected a number");
    }
  };
  auto integer = [&](const toml::table& tb, const char* key, const std::string& where) {
    std::optional<std::int64_t> out;
    if (auto n = tb.get(key)) {
      if (!n->is_integer()) fail(where + key, "expected an integer");
      out = n->value<std::int64_t>();
    }
    return out;
  };
  auto text = [&](const toml::table& tb, const char* key, const std::string& where) {
    std::optional<std::string> out;
    if (auto n = tb.get(key)) {
      if (!n->is_string()) fail(where + key, "expected a string");
      out = n->value<std::string>();
    }
    return out;
  };
  const std::vector<std::string> top_keys = {"excitation", "acquisition", "setup"};
  for (auto& [k, v] : t)
    if (std::find(top_keys.begin(), top_keys.end(), std::string(k.str())) == top_keys.end())
      fail(std::string(k.str()), "unknown section (excitation, acquisition, setup)");
    else if (!v.is_table())
      fail(std::string(k.str()), "expected a table ([" + std::string(k.str()) + "])");

  if (auto ex = t["excitation"].as_table()) {
    for (auto& [k, v] : *ex) {
      static const std::vector<std::string> known = {"kind", "amplitude_v", "decay_per_s", "frequency_hz",
                                                     "f_start_hz", "f_stop_hz", "f_step_hz", "seed",
                                                     "burst_fraction"};
      if (std::find(known.begin(), known.end(), std::string(k.str())) == known.end())
        fail("excitation." + std::string(k.str()), "unknown key");
    }
    if (auto kind = text(*ex, "kind", "excitation.")) {
      auto e = parse_excitation(*kind);
      if (!e || *e == Excitation::Arbitrary) fail("excitation.kind", "expected exp_decay, sine, chirp or noise");
      p.excitation.kind = *e;
    }
    auto& e = p.excitation;
    num(*ex, "amplitude_v", e.amplitude_v, "excitation.");
    num(*ex, "decay_per_s", e.decay_per_s, "excitation.");
    num(*ex, "frequency_hz", e.frequency_hz, "excitation.");
    num(*ex, "f_start_hz", e.f_start_hz, "excitation.");
    num(*ex, "f_stop_hz", e.f_stop_hz, "excitation.");
    num(*ex, "f_step_hz", e.f_step_hz, "excitation.");
    num(*ex, "burst_fraction", e.burst_fraction, "excitation.");
    if (auto s = integer(*ex, "seed", "excitation.")) e.noise_seed = static_cast<std::uint64_t>(*s);
  }
  if (auto aq = t["acquisition"].as_table()) {
    for (auto& [k, v] : *aq) {
      static const std::vector<std::string> known = {"sample_rate_hz", "samples", "pretrigger_samples",
                                                     "shots", "range_v"};
      if (std::find(known.begin(), known.end(), std::string(k.str())) == known.end())
        fail("acquisition." + std::string(k.str()), "unknown key");
    }
    num(*aq, "sample_rate_hz", p.sample_rate_hz, "acquisition.");
    num(*aq, "range_v", p.range_v, "acquisition.");
    if (auto v = integer(*aq, "samples", "acquisition.")) {
      if (*v < 0) fail("acquisition.samples", "must not be negative");
      p.samples = static_cast<std::size_t>(*v);
    }
    if (auto v = integer(*aq, "pretrigger_samples", "acquisition.")) {
      if (*v < 0) fail("acquisition.pretrigger_samples", "must not be negative");
      p.pretrigger_samples = static_cast<std::size_t>(*v);
    }
    if (auto v = integer(*aq, "shots", "acquisition.")) {
      if (*v < 1 || *v > MeasurementPlan::kMaxShots)
        fail("acquisition.shots", "must be in [1, " + std::to_string(MeasurementPlan::kMaxShots) + "]");
      p.shots = static_cast<int>(*v);
    }
  }
  p.setup.divider_r1_ohm = model::kSeedR1Ohm;
  if (auto su = t["setup"].as_table()) {
    for (auto& [k, v] : *su) {
      static const std::vector<std::string> known = {"r1_ohm", "transducer_id", "material", "notes",
                                                     "inner_diameter_m", "outer_diameter_m", "length_m",
                                                     "density_kg_m3"};
      if (std::find(known.begin(), known.end(), std::string(k.str())) == known.end())
        fail("setup." + std::string(k.str()), "unknown key");
    }
    num(*su, "r1_ohm", p.setup.divider_r1_ohm, "setup.");
    if (auto s = text(*su, "transducer_id", "setup.")) p.setup.transducer_id = *s;
    if (auto s = text(*su, "material", "setup.")) p.setup.material = *s;
    if (auto s = text(*su, "notes", "setup.")) p.setup.notes = *s;
    for (auto [key, dst] : {std::pair{"inner_diameter_m", &p.setup.inner_diameter_m},
                            std::pair{"outer_diameter_m", &p.setup.outer_diameter_m},
                            std::pair{"length_m", &p.setup.length_m},
                            std::pair{"density_kg_m3", &p.setup.density_kg_m3}}) {
      double v = 0;
      if ((*su)[key]) {
        num(*su, key, v, "setup.");
        *dst = v;
      }
    }
  }
  try {
    p.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("plan " + source + ": " + e.what());
  }
  return p;
}

}  // namespace piezo::acq
