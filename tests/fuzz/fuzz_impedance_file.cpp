// Fuzz harness: the measured-impedance importers of update/impedance_file.hpp.
// The input is a file's text, read both as CSV (f_hz,re_ohm,im_ohm) and as a
// Touchstone .s1p; every curve either reader accepts then goes through
// extract_features, as `piezobench update --file` does.
// Documented rejections: std::invalid_argument (bad content; the stream
// readers never meet "cannot open").
//
// An accepted curve promises: at least 5 points, as many impedances as
// frequencies, finite frequencies >= 0 in strictly ascending order, finite
// impedances with a finite magnitude (features work in dB of |Z|).
// extract_features promises: equal numbers of resonances and anti-resonances
// (at most max_modes), each a finite frequency inside the curve's range, a
// resonance below its anti-resonance, and a result the updater accepts
// (MeasuredFeatures::validate).
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <stdexcept>
#include <string>

#include "tests/fuzz/fuzz_support.hpp"
#include "update/impedance_file.hpp"

namespace {

using namespace piezo::update;

void check_curve(const ImpedanceCurve& c, const char* reader) {
  const std::size_t n = c.f_hz.size();
  FUZZ_CHECK(n >= 5 && c.z_ohm.size() == n, "%s: %zu frequencies, %zu impedances", reader, n,
             c.z_ohm.size());
  for (std::size_t i = 0; i < n; ++i) {
    FUZZ_CHECK(std::isfinite(c.f_hz[i]) && c.f_hz[i] >= 0, "%s: f[%zu] = %g", reader, i, c.f_hz[i]);
    FUZZ_CHECK(i == 0 || c.f_hz[i] > c.f_hz[i - 1], "%s: f[%zu] = %g not above f[%zu] = %g", reader,
               i, c.f_hz[i], i - 1, c.f_hz[i - 1]);
    FUZZ_CHECK(std::isfinite(c.z_ohm[i].real()) && std::isfinite(c.z_ohm[i].imag()) &&
                   std::isfinite(std::abs(c.z_ohm[i])),
               "%s: Z[%zu] = %g%+gj", reader, i, c.z_ohm[i].real(), c.z_ohm[i].imag());
  }

  ExtractedFeatures ex;
  const FeatureOptions opt;
  try {
    ex = extract_features(c, opt);
  } catch (const std::invalid_argument&) {
    return;  // no resonance pair or no capacitive point: documented
  }
  const auto& f = ex.features;
  if (std::getenv("PIEZO_FUZZ_DEBUG"))
    std::fprintf(stderr, "%s: %zu points, %zu resonance pairs, first %g / %g Hz, low |Z| %g ohm at %g Hz\n",
                 reader, c.f_hz.size(), f.resonances_hz.size(), f.resonances_hz[0], f.antiresonances_hz[0],
                 f.low_z_ohm, f.low_z_hz);
  FUZZ_CHECK(!f.resonances_hz.empty() && f.resonances_hz.size() == f.antiresonances_hz.size() &&
                 static_cast<int>(f.resonances_hz.size()) <= opt.max_modes,
             "%s: %zu resonances, %zu anti-resonances", reader, f.resonances_hz.size(),
             f.antiresonances_hz.size());
  for (std::size_t i = 0; i < f.resonances_hz.size(); ++i) {
    const double fr = f.resonances_hz[i], fa = f.antiresonances_hz[i];
    FUZZ_CHECK(std::isfinite(fr) && std::isfinite(fa) && fr >= c.f_hz.front() && fa <= c.f_hz.back(),
               "%s: pair %zu at %g / %g Hz, curve spans %g..%g Hz", reader, i, fr, fa, c.f_hz.front(),
               c.f_hz.back());
    FUZZ_CHECK(fr < fa, "%s: resonance %g Hz not below its anti-resonance %g Hz", reader, fr, fa);
  }
  FUZZ_CHECK(std::isfinite(ex.low_z_phase_deg), "%s: low-f phase %g", reader, ex.low_z_phase_deg);
  try {
    f.validate();
  } catch (const std::invalid_argument& e) {
    FUZZ_CHECK(false, "%s: extract_features gave features the updater refuses: %s", reader, e.what());
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  {
    std::istringstream in(text);
    ImpedanceCurve c;
    bool ok = true;
    try {
      c = parse_impedance_csv(in, "fuzz.csv");
    } catch (const std::invalid_argument&) {
      ok = false;
    }
    if (ok) check_curve(c, "csv");
  }
  {
    std::istringstream in(text);
    ImpedanceCurve c;
    bool ok = true;
    try {
      c = parse_touchstone_s1p(in, "fuzz.s1p");
    } catch (const std::invalid_argument&) {
      ok = false;
    }
    if (ok) check_curve(c, "s1p");
  }
  return 0;
}
