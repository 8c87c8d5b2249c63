// Fuzz harness: TOML measurement plans (acquisition/plan.hpp). The input is
// the text of a plan file, given to parse_plan_toml (what load_plan_toml runs
// on a file's contents). Documented rejection: std::invalid_argument.
//
// An accepted plan promises what the runner relies on:
//   - every number it holds is finite, within the limits validate() states,
//     and its set-up passes the capture writer's validate_setup (otherwise the
//     measurement fails after the instruments were configured, or writes a
//     capture the reader refuses);
//   - a bounded number of excitation steps and shots, each step playable
//     (synthesize: finite samples in [-1, 1]);
//   - it says what the file says: every known key that is present was used
//     with its value, and a key of the wrong TOML type was refused, not
//     silently replaced by the default (checked against toml++'s own parse).
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>
#include <toml++/toml.h>

#include "acquisition/capture.hpp"
#include "acquisition/plan.hpp"
#include "tests/fuzz/fuzz_support.hpp"

namespace {

using namespace piezo::acq;

void check_number(const toml::table* tb, const char* key, double got, const char* section) {
  if (!tb) return;
  const toml::node* n = tb->get(key);
  if (!n) return;
  auto v = n->value<double>();
  FUZZ_CHECK(v.has_value(), "%s.%s is not a number, yet the plan was accepted", section, key);
  FUZZ_CHECK(*v == got, "%s.%s = %g in the file, %g in the plan", section, key, *v, got);
}

// An integer key: accepted only as a TOML integer, used as written.
void check_integer(const toml::table* tb, const char* key, long double got, const char* section) {
  if (!tb) return;
  const toml::node* n = tb->get(key);
  if (!n) return;
  FUZZ_CHECK(n->is_integer(), "%s.%s is not an integer (TOML type %d), yet the plan was accepted",
             section, key, static_cast<int>(n->type()));
  const auto v = static_cast<long double>(*n->value<std::int64_t>());
  FUZZ_CHECK(v == got, "%s.%s = %Lg in the file, %Lg in the plan", section, key, v, got);
}

void check_string(const toml::table* tb, const char* key, const std::optional<std::string>& got,
                  const char* section) {
  if (!tb) return;
  const toml::node* n = tb->get(key);
  if (!n) return;
  FUZZ_CHECK(n->is_string(), "%s.%s is not a string, yet the plan was accepted", section, key);
  FUZZ_CHECK(got && *got == *n->value<std::string>(), "%s.%s not taken over", section, key);
}

void check_plan(const MeasurementPlan& p, std::string_view text) {
  const auto& e = p.excitation;
  // Finite numbers within the stated limits.
  for (auto [name, v] : {std::pair{"amplitude_v", e.amplitude_v}, std::pair{"decay_per_s", e.decay_per_s},
                         std::pair{"frequency_hz", e.frequency_hz}, std::pair{"f_start_hz", e.f_start_hz},
                         std::pair{"f_stop_hz", e.f_stop_hz}, std::pair{"f_step_hz", e.f_step_hz},
                         std::pair{"burst_fraction", e.burst_fraction},
                         std::pair{"sample_rate_hz", p.sample_rate_hz}, std::pair{"range_v", p.range_v},
                         std::pair{"r1_ohm", p.setup.divider_r1_ohm}})
    FUZZ_CHECK(std::isfinite(v), "accepted plan holds %s = %g", name, v);
  FUZZ_CHECK(p.samples >= kMinSamples && p.samples <= MeasurementPlan::kMaxSamples,
             "samples = %zu", p.samples);
  FUZZ_CHECK(p.pretrigger_samples < p.samples, "pretrigger %zu >= samples", p.pretrigger_samples);
  FUZZ_CHECK(p.shots >= 1 && p.shots <= MeasurementPlan::kMaxShots, "shots = %d", p.shots);
  FUZZ_CHECK(std::isfinite(p.daq_range_v()) && p.daq_range_v() > 0, "daq range %g", p.daq_range_v());
  try {
    validate_setup(p.setup, "plan");
  } catch (const CaptureError& err) {
    FUZZ_CHECK(false, "accepted plan has a set-up the capture writer refuses: %s", err.what());
  }
  // Bounded, playable steps. Count them before steps() builds them: an
  // unbounded count is the finding, not something to wait for.
  if (e.kind == Excitation::Sine && e.f_step_hz > 0) {
    const double n_steps = std::floor((e.f_stop_hz - e.f_start_hz) / e.f_step_hz) + 1;
    FUZZ_CHECK(n_steps <= static_cast<double>(MeasurementPlan::kMaxSteps), "%g stepped-sine steps",
               n_steps);
  }
  const auto steps = p.steps();
  FUZZ_CHECK(!steps.empty() && steps.size() <= MeasurementPlan::kMaxSteps, "%zu steps", steps.size());
  FUZZ_CHECK(steps.size() * static_cast<std::size_t>(p.shots) <= MeasurementPlan::kMaxShots,
             "%zu steps x %d shots", steps.size(), p.shots);
  const std::size_t post = p.samples - p.pretrigger_samples;
  const double nyq = 0.5 * p.sample_rate_hz;
  for (std::size_t k = 0; k < steps.size(); ++k) {
    const auto& s = steps[k];
    if (s.kind == Excitation::Sine)
      FUZZ_CHECK(s.frequency_hz > 0 && s.frequency_hz < nyq, "step %zu at %g Hz (Nyquist %g)", k,
                 s.frequency_hz, nyq);
    if (post > (1u << 15) || (k > 0 && k + 1 < steps.size())) continue;  // first and last only
    const auto w = synthesize(s, p.sample_rate_hz, post);
    FUZZ_CHECK(w.size() == post, "synthesize gave %zu samples for %zu", w.size(), post);
    for (std::size_t i = 0; i < w.size(); ++i)
      FUZZ_CHECK(std::isfinite(w[i]) && std::abs(w[i]) <= 1.0 + 1e-12,
                 "step %zu sample %zu = %g (kind %d, burst_fraction %g)", k, i, w[i],
                 static_cast<int>(s.kind), s.burst_fraction);
  }

  // The plan says what the file says.
  toml::table t = toml::parse(text);  // parse_plan_toml accepted the same text
  for (const char* section : {"excitation", "acquisition", "setup"})
    if (const toml::node* n = t.get(section))
      FUZZ_CHECK(n->is_table(), "[%s] is not a table, yet the plan was accepted", section);
  const toml::table* ex = t["excitation"].as_table();
  const toml::table* aq = t["acquisition"].as_table();
  const toml::table* su = t["setup"].as_table();
  if (ex && ex->get("kind")) {
    const toml::node* k = ex->get("kind");
    FUZZ_CHECK(k->is_string(), "excitation.kind is not a string, yet the plan was accepted");
    FUZZ_CHECK(to_string(e.kind) == *k->value<std::string>(), "excitation.kind not taken over");
  }
  check_number(ex, "amplitude_v", e.amplitude_v, "excitation");
  check_number(ex, "decay_per_s", e.decay_per_s, "excitation");
  check_number(ex, "frequency_hz", e.frequency_hz, "excitation");
  check_number(ex, "f_start_hz", e.f_start_hz, "excitation");
  check_number(ex, "f_stop_hz", e.f_stop_hz, "excitation");
  check_number(ex, "f_step_hz", e.f_step_hz, "excitation");
  check_number(ex, "burst_fraction", e.burst_fraction, "excitation");
  if (ex && ex->get("seed")) {
    const toml::node* n = ex->get("seed");
    FUZZ_CHECK(n->is_integer(), "excitation.seed is not an integer, yet the plan was accepted");
    FUZZ_CHECK(static_cast<std::uint64_t>(*n->value<std::int64_t>()) == e.noise_seed,
               "excitation.seed not taken over");
  }
  check_number(aq, "sample_rate_hz", p.sample_rate_hz, "acquisition");
  check_number(aq, "range_v", p.range_v, "acquisition");
  check_integer(aq, "samples", static_cast<long double>(p.samples), "acquisition");
  check_integer(aq, "pretrigger_samples", static_cast<long double>(p.pretrigger_samples), "acquisition");
  check_integer(aq, "shots", p.shots, "acquisition");
  check_number(su, "r1_ohm", p.setup.divider_r1_ohm, "setup");
  check_string(su, "transducer_id", p.setup.transducer_id, "setup");
  check_string(su, "material", p.setup.material, "setup");
  check_string(su, "notes", p.setup.notes, "setup");
  for (auto [key, v] : {std::pair{"inner_diameter_m", &p.setup.inner_diameter_m},
                        std::pair{"outer_diameter_m", &p.setup.outer_diameter_m},
                        std::pair{"length_m", &p.setup.length_m},
                        std::pair{"density_kg_m3", &p.setup.density_kg_m3}}) {
    if (su && su->get(key)) {
      FUZZ_CHECK(v->has_value(), "setup.%s dropped", key);
      check_number(su, key, **v, "setup");
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  MeasurementPlan p;
  try {
    p = parse_plan_toml(text, "fuzz.toml");
  } catch (const std::invalid_argument&) {
    return 0;  // documented rejection
  }
  check_plan(p, text);
  return 0;
}
