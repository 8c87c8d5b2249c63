#include "acquisition/capture.hpp"

#include <cmath>
#include <cstdio>

namespace piezo::acq {

namespace {
constexpr std::pair<Excitation, std::string_view> kExcitations[] = {
    {Excitation::ExpDecay, "exp_decay"}, {Excitation::Sine, "sine"}, {Excitation::Chirp, "chirp"},
    {Excitation::Noise, "noise"},        {Excitation::Arbitrary, "arbitrary"}};
constexpr std::pair<Role, std::string_view> kRoles[] = {
    {Role::Dut, "dut"}, {Role::Open, "open"}, {Role::Short, "short"}, {Role::Load, "load"}};

bool positive_finite(const std::optional<double>& v) { return !v || (std::isfinite(*v) && *v > 0); }
}  // namespace

std::string_view to_string(Excitation e) {
  for (auto& [k, s] : kExcitations)
    if (k == e) return s;
  return "arbitrary";
}
std::string_view to_string(Role r) {
  for (auto& [k, s] : kRoles)
    if (k == r) return s;
  return "dut";
}
std::optional<Excitation> parse_excitation(std::string_view s) {
  for (auto& [k, n] : kExcitations)
    if (n == s) return k;
  return std::nullopt;
}
std::optional<Role> parse_role(std::string_view s) {
  for (auto& [k, n] : kRoles)
    if (n == s) return k;
  return std::nullopt;
}

model::TubeGeometry Setup::geometry() const {
  model::TubeGeometry g;
  if (inner_diameter_m) g.inner_diameter_m = *inner_diameter_m;
  if (outer_diameter_m) g.outer_diameter_m = *outer_diameter_m;
  if (length_m) g.length_m = *length_m;
  if (density_kg_m3) g.density_kg_m3 = *density_kg_m3;
  return g;
}

CaptureError::CaptureError(std::string file, std::string h5path, std::string problem)
    : std::runtime_error(file + ": " + h5path + ": " + problem),
      file_(std::move(file)),
      h5path_(std::move(h5path)),
      problem_(std::move(problem)) {}

void validate_setup(const Setup& s, const std::string& file) {
  if (!(std::isfinite(s.divider_r1_ohm) && s.divider_r1_ohm > 0))
    throw CaptureError(file, "/setup/divider_r1_ohm",
                       "must be a positive finite resistance, got " + std::to_string(s.divider_r1_ohm));
  const std::pair<const char*, const std::optional<double>*> geo[] = {
      {"inner_diameter_m", &s.inner_diameter_m},
      {"outer_diameter_m", &s.outer_diameter_m},
      {"length_m", &s.length_m},
      {"density_kg_m3", &s.density_kg_m3}};
  for (auto& [name, v] : geo)
    if (!positive_finite(*v))
      throw CaptureError(file, std::string("/setup/") + name, "must be positive and finite");
}

void validate_shot_attributes(const Shot& shot, std::size_t n, const std::string& file,
                              const std::string& p) {
  if (!(std::isfinite(shot.sample_rate_hz) && shot.sample_rate_hz > 0))
    throw CaptureError(file, p + "/sample_rate_hz",
                       "must be a positive finite rate, got " + std::to_string(shot.sample_rate_hz));
  if (!(shot.sample_rate_hz >= kMinRateHz && shot.sample_rate_hz <= kMaxRateHz)) {
    char b[160];
    std::snprintf(b, sizeof b, "implausible sample rate %.6g Hz (accepted: %.0g to %.0g Hz)",
                  shot.sample_rate_hz, kMinRateHz, kMaxRateHz);
    throw CaptureError(file, p + "/sample_rate_hz", b);
  }
  if (n > kMaxSamples)
    throw CaptureError(file, p + "/v1",
                       "implausible length: " + std::to_string(n) + " samples (this reader takes at most " +
                           std::to_string(kMaxSamples) + " per signal)");
  if (shot.pretrigger_samples < 0 || static_cast<std::size_t>(shot.pretrigger_samples) >= n)
    throw CaptureError(file, p + "/pretrigger_samples",
                       "must be in [0, N), got " + std::to_string(shot.pretrigger_samples));
  for (auto [name, v] : {std::pair{"daq_range_v", &shot.daq_range_v},
                         std::pair{"v1_range_v", &shot.v1_range_v},
                         std::pair{"v2_range_v", &shot.v2_range_v}})
    if (!positive_finite(*v))
      throw CaptureError(file, p + "/" + name, "must be positive and finite");
  if (shot.adc_bits && (*shot.adc_bits < 1 || *shot.adc_bits > 32))
    throw CaptureError(file, p + "/adc_bits",
                       "must be 1..32, got " + std::to_string(*shot.adc_bits));
  if (shot.role == Role::Load && !(shot.load_ohm && std::isfinite(*shot.load_ohm) && *shot.load_ohm > 0))
    throw CaptureError(file, p + "/load_ohm", "role 'load' needs a positive load_ohm");
  if (shot.load_parallel_f && !(std::isfinite(*shot.load_parallel_f) && *shot.load_parallel_f >= 0))
    throw CaptureError(file, p + "/load_parallel_f", "must be finite and >= 0");
}

void validate_shot(const Shot& shot, const std::string& file, const std::string& p) {
  validate_shot_attributes(shot, shot.v1.size(), file, p);
  if (shot.v1.size() != shot.v2.size())
    throw CaptureError(file, p, "length mismatch: v1 has " + std::to_string(shot.v1.size()) +
                                    " samples, v2 has " + std::to_string(shot.v2.size()));
  if (shot.v1.size() < kMinSamples)
    throw CaptureError(file, p + "/v1",
                       "too short: " + std::to_string(shot.v1.size()) + " samples, need at least " +
                           std::to_string(kMinSamples));
  for (const char* ch : {"v1", "v2"}) {
    const auto& v = (ch[1] == '1') ? shot.v1 : shot.v2;
    for (std::size_t i = 0; i < v.size(); ++i)
      if (!std::isfinite(v[i]))
        throw CaptureError(file, p + "/" + ch,
                           std::string(std::isnan(v[i]) ? "NaN" : "Inf") + " at sample " +
                               std::to_string(i));
    if (const auto range = shot.range_v(ch[1] == '1' ? 1 : 2)) {
      const double limit = kRangeMargin * *range;
      for (std::size_t i = 0; i < v.size(); ++i)
        if (std::abs(v[i]) > limit) {
          char b[200];
          std::snprintf(b, sizeof b,
                        "sample %zu is %.6g V, outside the declared range +-%.6g V (more than "
                        "%.2f x full scale: no converter of that range records it)",
                        i, v[i], *range, kRangeMargin);
          throw CaptureError(file, p + "/" + ch, b);
        }
    }
  }
}

}  // namespace piezo::acq
