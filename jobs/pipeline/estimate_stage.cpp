// The pipeline's room (jobs/pipeline), estimate stage: Z(ω) of the capture by
// Prony-SS (features refined by the port-model fit), with the FFT ratio and
// the cross-spectra as overlays.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "acquisition/divider_record.hpp"
#include "acquisition/estimators/estimator.hpp"
#include "acquisition/impedance_assessment.hpp"
#include "dsp/divider_baseline.hpp"
#include "dsp/cross_spectra.hpp"
#include "dsp/fft_ratio.hpp"
#include "dsp/prony_impedance.hpp"
#include "dsp/prony_ss.hpp"
#include "jobs/pipeline/stages.hpp"
#include "update/port_fit.hpp"

namespace piezo::jobs::detail {

namespace {

// "measured (LABEL)", LABEL the estimator's in the registry (acquisition/estimators/).
Curve curve_of(const std::string& estimator, const dsp::ImpedanceResult& r) {
  Curve c;
  c.label = "measured (" + acq::builtin_estimators().at(estimator).label + ")";
  c.estimator = estimator;
  c.f_hz.assign(r.f_hz.data(), r.f_hz.data() + r.f_hz.size());
  c.z_ohm.assign(r.z_ohm.data(), r.z_ohm.data() + r.z_ohm.size());
  return c;
}

}  // namespace

// Z(ω) of the capture: Prony-SS on the first transient "dut" shot (the
// estimate the update uses), with the direct FFT ratio and the averaged
// cross-spectra of all such shots as overlays.
dsp::ImpedanceResult estimate(const acq::Capture& cap, bool refine_features, PipelineResult& out) {
  const std::optional<dsp::FixtureCalibration>& fx = out.fixture;
  bool fixture_in_fit = false;  // the port fit ran with the measured fixture in its circuit
  std::vector<const acq::Shot*> shots;
  for (const auto& s : cap.shots)
    if (s.role == acq::Role::Dut && s.excitation != acq::Excitation::Sine) shots.push_back(&s);
  if (shots.empty())
    throw std::invalid_argument("the capture holds no transient \"dut\" shot to estimate Z from");
  const acq::Shot& first = *shots.front();
  // The one estimate's band, grid and record length (acq::default_estimate:
  // `impedance` and `figures` use the same by default).
  const acq::EstimateDefaults est = acq::default_estimate(first);
  const double fmax = est.fmax_hz, step = est.step_hz;
  // Repeated shots of one drive are averaged sample by sample before the fit
  // (white noise drops by √N; the transient is identical from shot to shot).
  std::vector<double> v1(first.v1), v2(first.v2);
  int averaged = 1;
  for (std::size_t k = 1; k < shots.size(); ++k) {
    const auto& s = *shots[k];
    if (s.samples() != first.samples() || s.sample_rate_hz != first.sample_rate_hz ||
        s.pretrigger_samples != first.pretrigger_samples || s.excitation != first.excitation ||
        s.amplitude_v != first.amplitude_v || s.decay_per_s != first.decay_per_s)
      continue;
    for (std::size_t i = 0; i < v1.size(); ++i) {
      v1[i] += s.v1[i];
      v2[i] += s.v2[i];
    }
    ++averaged;
  }
  for (std::size_t i = 0; i < v1.size(); ++i) {
    v1[i] /= averaged;
    v2[i] /= averaged;
  }
  out.shots_averaged = averaged;
  dsp::DividerRecord avg{v1, v2, first.sample_rate_hz, cap.setup.divider_r1_ohm,
                         static_cast<std::size_t>(std::max<std::int64_t>(0, first.pretrigger_samples)),
                         first.range_v(1), first.range_v(2)};
  {  // A real bench's slow disturbances on channel 1 − channel 2 (issue 33;
     // dsp/divider_baseline.hpp): said, not removed (the removal's own noise in
     // the lowest bins costs as much; the update's output-error fit models them).
    const auto bl = dsp::estimate_divider_baseline(avg);
    if (bl.found)
      out.warnings.push_back("the impedance estimate's lowest bins (below " + std::to_string(static_cast<long>(bl.band_hz)) +
                             " Hz) hold a slow baseline of channel 1 - channel 2: rms " + std::to_string(bl.rms_v) +
                             " V (delta chi2 " + std::to_string(static_cast<long>(bl.delta_chi2)) +
                             "); the update's output-error fit models it");
  }
  dsp::PronyImpedanceOptions po;
  po.ramp_onset = true;  // the AWG ramps from idle at -dt onto its first sample
  // The samples before the first decimated one enter Z as recorded: the tube's
  // modes above the band, which the noise-set order leaves out (see
  // acq::bench_prony_options).
  po.direct_samples = dsp::PronyImpedanceOptions::kDirectFilterLength;
  const std::size_t post = first.samples() - static_cast<std::size_t>(first.pretrigger_samples);
  po.prep.max_samples = est.max_samples;
  po.prony.band_hz = fmax;
  po.features.fmin_hz = step;
  auto prony = dsp::impedance_prony(avg, dsp::make_grid(step, fmax, step), po);
  // The first three resonance / anti-resonance pairs and the capacitance are
  // refined by the output-error fit of the modal port model to the same
  // samples (update/port_fit.hpp): Prony's zeros of Z(s) carry a truncation
  // bias where the noise sets its order (+0.2 … 0.3 % on the third resonance,
  // +1 % on nu12 after the update). Prony's values stay when the fit fails.
  if (refine_features) {
    auto& fr = prony.features.resonances;
    auto& fa = prony.features.antiresonances;
    const std::size_t n = std::min<std::size_t>({3, fr.size(), fa.size()});
    const std::size_t pre = avg.pretrigger_samples, nfit = std::min(post, po.prep.max_samples);
    try {
      if (n == 0 || !(prony.features.capacitance_f > 0))
        throw std::invalid_argument("no features to start from");
      update::PortFitStart st;
      for (std::size_t k = 0; k < n; ++k) {
        st.resonances_hz.push_back(fr[k].f_hz);
        st.antiresonances_hz.push_back(fa[k].f_hz);
        st.damping_ratios.push_back(fr[k].damping_ratio);
      }
      st.capacitance_f = prony.features.capacitance_f;
      double m1 = 0, m2 = 0;  // DAQ offsets, as dsp's front end removes them
      for (std::size_t i = 0; pre >= 16 && i < pre; ++i) {
        m1 += v1[i] / static_cast<double>(pre);
        m2 += v2[i] / static_cast<double>(pre);
      }
      // Start one sample before t = 0 (the idle level) when there is a
      // pretrigger: the fit takes its input as at rest before the first sample
      // and linear between samples, which is then the AWG's ramp onto the
      // burst (drivers/sim/sim_bench.cpp) rather than a jump half a sample off.
      const std::size_t lead = pre > 0 ? 1 : 0;
      // A measured fixture (calibration shots) goes into the circuit the port
      // is simulated in: true R1, Cp at node 2, lead R; channel 2's delay τ is
      // moved to the input (the response at t_k − τ to v1 is the response at
      // t_k to v1 delayed by τ: v1 interpolated at k − τ·fs, idle before).
      update::PortFitOptions pfo;
      double r1_fit = cap.setup.divider_r1_ohm;
      double d = 0.0;
      if (fx) {
        r1_fit *= 1.0 + fx->r1_error.value_or(0.0);
        pfo.fixture_capacitance_f = std::max(0.0, fx->fixture_capacitance_f.value_or(0.0));
        pfo.lead_resistance_ohm = std::max(0.0, fx->lead_resistance_ohm.value_or(0.0));
        d = fx->skew_s.value_or(0.0) * first.sample_rate_hz;
      }
      auto v1_at = [&](double q) {  // v1 − offset at fractional record index q
        if (q <= 0) return v1[0] - m1;
        const auto k = static_cast<std::size_t>(std::floor(q));
        if (k + 1 >= v1.size()) return v1.back() - m1;
        const double w = q - double(k);
        return (1 - w) * v1[k] + w * v1[k + 1] - m1;
      };
      std::vector<double> a(nfit), b(nfit);
      for (std::size_t i = 0; i < nfit; ++i) {
        a[i] = v1_at(double(pre - lead + i) - d);
        b[i] = v2[pre - lead + i] - m2;
      }
      const auto fit = update::fit_port_model(a, b, first.sample_rate_hz, r1_fit, st, pfo);
      if (!fit.converged) throw std::runtime_error(fit.message);
      for (std::size_t k = 0; k < n; ++k) {
        fr[k].f_hz = fit.features.resonances_hz[k];
        fa[k].f_hz = fit.features.antiresonances_hz[k];
        if (k < fit.features.resonance_sigma_hz.size()) {
          fr[k].sigma_hz = fit.features.resonance_sigma_hz[k];
          fa[k].sigma_hz = fit.features.antiresonance_sigma_hz[k];
        }
      }
      prony.features.capacitance_f = fit.features.low_frequency_capacitance();
      if (fit.features.low_z_sigma_ohm > 0)  // σ_C/C = σ_|Z|/|Z| at f_L (issue 40: the seed chain needs it)
        prony.features.capacitance_sigma_f =
            prony.features.capacitance_f * fit.features.low_z_sigma_ohm / fit.features.low_z_ohm;
      fixture_in_fit = fx.has_value();
    } catch (const std::exception& e) {
      out.warnings.push_back(
          std::string("port-model refinement of the features skipped (Prony's kept): ") + e.what());
    }
  }
  // Without the port fit, Prony's capacitance holds the fixture's: Z_m = Z_v2/(1 + r1_error)
  // with the fixture capacitance Cp across the v2 node, so C_m = (C + Cp)·(1 + r1_error).
  if (fx && !fixture_in_fit && (fx->fixture_capacitance_f || fx->r1_error)) {
    const double c_m = prony.features.capacitance_f;
    const double c = c_m / (1.0 + fx->r1_error.value_or(0.0)) - fx->fixture_capacitance_f.value_or(0.0);
    if (c > 0) {
      prony.features.capacitance_f = c;
      char note[200];
      std::snprintf(note, sizeof note,
                    "capacitance corrected for the measured fixture: %.5g F measured -> %.5g F of the transducer", c_m, c);
      out.warnings.push_back(note);
    } else {
      out.warnings.push_back("the measured fixture capacitance exceeds the measured capacitance: not corrected");
    }
  }
  out.curves.push_back(curve_of("prony", prony));
  for (const auto& f : prony.features.resonances) out.resonances_hz.push_back(f.f_hz);
  for (const auto& f : prony.features.antiresonances) out.antiresonances_hz.push_back(f.f_hz);
  if (prony.prony) {
    out.singular_values = prony.prony->singular_values_normalized;
    out.order = static_cast<int>(prony.prony->order);
  }
  try {
    dsp::FftRatioOptions fo;
    fo.fmin_hz = step;
    fo.fmax_hz = fmax;
    out.curves.push_back(curve_of("fft", dsp::impedance_fft(acq::divider_record(cap, first), fo)));
    std::vector<dsp::DividerRecord> recs;
    for (const auto* s : shots)
      if (s->excitation == first.excitation) recs.push_back(acq::divider_record(cap, *s));
    dsp::CrossSpectraOptions xo;
    xo.fmin_hz = step;
    xo.fmax_hz = fmax;
    out.curves.push_back(curve_of("xspec", dsp::impedance_xspec(recs, xo)));
  } catch (const std::exception& e) {
    out.warnings.push_back(std::string("overlay estimators: ") + e.what());
  }
  return prony;
}

}  // namespace piezo::jobs::detail
