#include "fixture_study.hpp"

#include <cmath>

#include "acquisition/calibration_plan.hpp"
#include "acquisition/capture_file.hpp"
#include "acquisition/runner.hpp"
#include "dsp/features.hpp"

namespace piezo::test {

acq::SimSpec fixture_spec(const FixtureSetting& s, std::uint64_t seed, double noise_rel) {
  acq::SimSpec spec;
  spec.isotropic = true;
  spec.set = "YE11=6.66e10,nu12=0.3333,d31=-210e-12,epsT33_rel=2294";
  spec.noise_rel = noise_rel;
  spec.seed = seed;
  spec.effects.parallel_capacitance_f = s.cp_f;
  spec.effects.series_resistance_ohm = s.rs_ohm;
  spec.effects.r1_tolerance = s.r1_tolerance;
  spec.effects.channel_skew_s = s.skew_s;
  return spec;
}

acq::Capture measure_capture(const acq::SimSpec& spec, int shots, bool calibrate,
                             const std::filesystem::path& file) {
  acq::MeasurementPlan plan;
  plan.setup.divider_r1_ohm = 3140.0;
  plan.shots = shots;
  auto bench =
      acq::open_bench({"sim", std::nullopt}, acq::make_sim_bench(spec, plan.setup.divider_r1_ohm));
  acq::RunnerOptions ro;
  ro.overwrite = true;
  if (calibrate) {
    ro.calibration = acq::parse_calibration_list("open,short,load", 1000.0);
    ro.connect_standard = acq::make_standard_connector(bench, nullptr);
  }
  acq::run_measurement(bench, plan, file, ro);
  return acq::read_capture(file);
}

std::vector<double> true_peaks(const std::function<std::complex<double>(double)>& truth,
                               double fmax) {
  const auto ft = dsp::find_features(truth, 500.0, 1.05 * fmax, 10.0);
  std::vector<double> p;
  for (const auto& f : ft.resonances) p.push_back(f.f_hz);
  for (const auto& f : ft.antiresonances) p.push_back(f.f_hz);
  return p;
}

bool near_peak(double f, const std::vector<double>& peaks) {
  for (double p : peaks)
    if (std::abs(f - p) < 0.015 * p) return true;
  return false;
}

MaxError max_error(const std::vector<double>& f, const std::vector<std::complex<double>>& z,
                   const std::function<std::complex<double>(double)>& truth,
                   const std::vector<double>& peaks) {
  MaxError e;
  for (std::size_t k = 0; k < f.size(); ++k) {
    if (near_peak(f[k], peaks)) continue;
    const std::complex<double> zt = truth(f[k]);
    const double m = std::abs(std::abs(z[k]) / std::abs(zt) - 1.0) * 100.0;
    const double p = std::abs(std::arg(z[k] / zt)) * 180.0 / M_PI;
    if (m > e.mag_pct) e.mag_pct = m, e.mag_f_hz = f[k];
    if (p > e.phase_deg) e.phase_deg = p, e.phase_f_hz = f[k];
    ++e.points;
  }
  return e;
}

}  // namespace piezo::test
