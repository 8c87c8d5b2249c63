#include "acquisition/impedance_assessment.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>

#include "acquisition/divider_record.hpp"
#include "acquisition/estimators/estimator.hpp"
#include "dsp/deskew.hpp"
#include "dsp/features.hpp"

namespace piezo::acq {

EstimateDefaults default_estimate(const Shot& first) {
  EstimateDefaults d;
  const double fs = first.sample_rate_hz;
  const std::size_t post =
      first.samples() - static_cast<std::size_t>(std::clamp<std::int64_t>(first.pretrigger_samples, 0,
                                                                         static_cast<std::int64_t>(first.samples())));
  d.fmax_hz = std::min(kDefaultEstimateBandHz, fs / 4);
  // Prony decimates by D = fs/(5 fmax) (dsp::decimation_factor); a record
  // shorter than 64 D keeps too few decimated samples for its Hankel matrix:
  // the band widens (D shrinks) to what the record carries, fs/4 at most.
  if (post > 0 && static_cast<double>(post) < 64.0 * fs / (5.0 * d.fmax_hz))
    d.fmax_hz = std::min(fs / 4, 64.0 * fs / (5.0 * static_cast<double>(post)));
  d.step_hz = std::max(std::min(kDefaultEstimateStepHz, d.fmax_hz / 100), d.fmax_hz / 2000);
  d.fmin_hz = d.step_hz;
  d.max_samples = std::min(kDefaultEstimateSamples, post);
  return d;
}


namespace {

std::vector<const Shot*> dut_shots(const Capture& cap, const AssessmentOptions& opt) {
  if (opt.shot) {
    if (*opt.shot >= cap.shots.size())
      throw std::invalid_argument("shot " + std::to_string(*opt.shot) +
                                  " does not exist (the capture has " +
                                  std::to_string(cap.shots.size()) + ")");
    const Shot& s = cap.shots[*opt.shot];
    if (s.role != Role::Dut)
      throw std::invalid_argument("shot " + s.name + " is a calibration shot (role \"" +
                                  std::string(to_string(s.role)) +
                                  "\"), not the device under test");
    return {&s};
  }
  const Shot* first = nullptr;
  for (const auto& s : cap.shots)
    if (s.role == Role::Dut && s.excitation == Excitation::ExpDecay) {
      first = &s;
      break;
    }
  if (!first)
    for (const auto& s : cap.shots)
      if (s.role == Role::Dut && s.excitation != Excitation::Sine) {
        first = &s;
        break;
      }
  if (!first) throw std::invalid_argument("the capture holds no transient \"dut\" shot");
  std::vector<const Shot*> out;
  for (const auto& s : cap.shots)
    if (s.role == Role::Dut && same_drive(*first, s)) out.push_back(&s);
  return out;
}

std::vector<dsp::DividerRecord> views(const std::vector<OwnedRecord>& recs) {
  std::vector<dsp::DividerRecord> v;
  for (const auto& r : recs) v.push_back(r.view());
  return v;
}

// One estimate from owned records by the registry's entry (averaged, or as segments: its caps).
dsp::ImpedanceResult estimate(const EstimatorEntry& e, const std::vector<OwnedRecord>& recs, const EstimateBand& b,
                              const AssessmentOptions& opt, std::optional<std::size_t> order,
                              std::optional<std::size_t> bootstrap) {
  const auto v = views(recs);
  return e.estimate(EstimateInput{v, {}, b, opt, order, bootstrap});
}

OwnedRecord single(const Capture& cap, const Shot& s) {
  const Shot* p = &s;
  return average_shots(cap, std::span<const Shot* const>(&p, 1));
}

}  // namespace

ImpedanceAssessment assess_impedance(const Capture& cap, const AssessmentOptions& opt) {
  const EstimatorRegistry& estimators = builtin_estimators();
  const EstimatorEntry* est = estimators.find(opt.method);
  if (!est || !est->caps.transient_shots)
    throw std::invalid_argument(
        "assess_impedance: method '" + opt.method + "' (expected " +
        join_keys(estimators.keys([](const EstimatorEntry& e) { return e.caps.transient_shots; })) + ")");
  ImpedanceAssessment out;
  const auto shots = dut_shots(cap, opt);
  for (const Shot* s : shots) out.shots.push_back(s->name);
  const double fs = shots.front()->sample_rate_hz;
  EstimateBand b;
  b.fmax_hz = opt.fmax_hz > 0 ? opt.fmax_hz : fs / 4;
  if (!(b.fmax_hz <= fs / 2))
    throw std::invalid_argument("fmax above the Nyquist frequency (" + std::to_string(fs / 2) +
                                " Hz)");
  b.step_hz = opt.step_hz > 0 ? opt.step_hz : b.fmax_hz / 2000;
  b.fmin_hz = opt.fmin_hz > 0 ? opt.fmin_hz : b.step_hz;
  if (!(b.fmin_hz < b.fmax_hz)) throw std::invalid_argument("fmin must lie below fmax");

  // Calibration (skew and standards) from the capture's calibration shots.
  if (opt.compensate) {
    CaptureCalibrationOptions co;
    co.fmin_hz = 0.0;
    co.fmax_hz = b.fmax_hz;
    co.degree = opt.standard_degree;
    co.model = opt.model;
    co.deskew = opt.deskew;
    out.calibration = calibrate_from_capture(cap, co);
    if (out.calibration) {
      out.skew_applied_s = out.calibration->skew_applied_s;
      out.skew_source = out.calibration->skew_source;
      out.model = out.calibration->model;
      for (const auto& n : out.calibration->notes) out.notes.push_back(n);
    } else if (opt.model && *opt.model != dsp::FixtureModel::None) {
      throw std::invalid_argument(
          "fixture compensation '" + std::string(dsp::to_string(*opt.model)) +
          "' asked for, but the capture holds no calibration shot (role open/short/load)");
    }
  }
  if (!out.calibration && opt.skew_s && opt.deskew) {
    out.skew_applied_s = *opt.skew_s;
    out.skew_source = "given (a stored skew)";
  }
  out.model_description = dsp::describe(out.model);

  // The records are not altered by the calibration (below), so the estimate
  // before compensation and deskew is the same estimate: computed once.
  std::vector<OwnedRecord> ready;
  out.baseline_removed = opt.baseline && opt.baseline_remove;
  for (const Shot* s : shots) {
    ready.push_back(single(cap, *s));
    if (opt.baseline) {  // a real bench's slow disturbances, off channel 1 − channel 2 (issue 33)
      auto bl = dsp::estimate_divider_baseline(ready.back().view(), opt.baseline_options);
      auto& rec = ready.back();
      if (bl.found && opt.baseline_remove)
        for (std::size_t i = 0; i < bl.samples.size(); ++i) rec.v1[rec.pretrigger_samples + i] -= bl.samples[i];
      if (bl.found) bl.note += opt.baseline_remove ? " - removed from channel 1" : " - kept (--remove-baseline removes it)";
      if (bl.found || !bl.tested) out.notes.push_back("shot " + s->name + ": " + bl.note);
      out.baselines.push_back(std::move(bl));
    }
    // Channel 2's delay is removed from Z below (T = T_m·e^{+jωτ}), not from
    // the records: resampling channel 2 interpolates its response across the
    // drive's kinks at its onset and at t = 0 (-0.3 ... -2.8 points of |Z|
    // error near 84 kHz in test_fixture_acceptance).
  }
  const AssessmentOptions& o2 = opt;
  out.result = estimate(*est, ready, b, o2, std::nullopt, std::nullopt);
  out.uncompensated = out.result;  // its band (z_sigma_ohm) belongs to the corrected estimate
  out.uncompensated.z_sigma_ohm.resize(0);
  const bool zdesk = opt.deskew && out.skew_applied_s != 0.0;
  if (zdesk) dsp::deskew_impedance(out.result, ready.front().r1_ohm, out.skew_applied_s);
  const std::optional<std::size_t> order =
      out.result.prony ? std::optional<std::size_t>(out.result.prony->order) : std::nullopt;
  std::optional<dsp::FixtureCompensation> comp;
  if (out.calibration) comp = out.calibration->compensation();
  // The standards' own uncertainty at each point (before correcting Z in place).
  Eigen::VectorXd sigma_std;
  if (comp) {
    sigma_std.resize(out.result.f_hz.size());
    for (Eigen::Index k = 0; k < sigma_std.size(); ++k)
      sigma_std[k] = comp->corrected_sigma(out.result.f_hz[k], out.result.z_ohm[k], 0.0);
    comp->apply(out.result);
    dsp::FeatureOptions fo = opt.prony.features;
    fo.fmin_hz = b.fmin_hz;
    out.result.features =
        dsp::find_features(out.result.f_hz, out.result.z_ohm, out.result.z_sigma_ohm, fo);
    out.notes.push_back(
        "features of the compensated estimate are |Z| extrema on the grid (not Prony zeros/poles)");
  }

  // Uncertainty band.
  UncertaintySource src = opt.uncertainty;
  if (src == UncertaintySource::Auto)
    src = ready.size() >= 3 ? UncertaintySource::Shots : UncertaintySource::Noise;
  if (src == UncertaintySource::Shots && ready.size() < 2) {
    out.notes.push_back(
        "uncertainty: a bootstrap over shots needs >= 2 shots; noise propagation used");
    src = UncertaintySource::Noise;
  }
  if (src == UncertaintySource::Shots) {
    auto reps = dsp::bootstrap_over_shots(ready.size(), opt.bootstrap, opt.seed,
                                          [&](const std::vector<std::size_t>& idx) {
                                            std::vector<OwnedRecord> pick;
                                            for (auto i : idx) pick.push_back(ready[i]);
                                            auto r = estimate(*est, pick, b, o2, order, 0);
                                            if (zdesk) dsp::deskew_impedance(r, ready.front().r1_ohm, out.skew_applied_s);
                                            if (comp)
                                              for (Eigen::Index k = 0; k < r.f_hz.size(); ++k)
                                                r.z_ohm[k] = comp->correct(r.f_hz[k], r.z_ohm[k]);
                                            return Eigen::VectorXcd(r.z_ohm);
                                          });
    if (reps.size() >= 2) {
      out.band = dsp::band_from_replicates(
          out.result.f_hz, out.result.z_ohm, reps, ready.size(), opt.coverage_factor,
          "bootstrap over " + std::to_string(ready.size()) + " shots (" +
              std::to_string(reps.size()) + " replicates)");
      if (comp) {
        dsp::add_in_quadrature(*out.band, sigma_std);
        out.band->source += " + fixture standards";
      }
    } else {
      out.notes.push_back("uncertainty: the bootstrap replicates failed; noise propagation used");
      src = UncertaintySource::Noise;
    }
  }
  if (src == UncertaintySource::Noise) {
    const bool have = out.result.z_sigma_ohm.size() == out.result.f_hz.size();
    // The estimators' noise propagation assumes white noise; slow noise that
    // the baseline test measured in the lowest bins (1/f wander: issue 33)
    // widens σ there, the shots' mean excess, continued above as 1/f.
    if (have && !out.baselines.empty()) {
      double widest = 1;
      for (Eigen::Index k = 0; k < out.result.f_hz.size(); ++k) {
        double e = 0;
        for (const auto& bl : out.baselines) e += bl.excess_noise(out.result.f_hz[k]);
        e /= double(out.baselines.size());
        out.result.z_sigma_ohm[k] *= std::sqrt(e);
        widest = std::max(widest, e);
      }
      if (widest > 1)
        out.notes.push_back("the lowest bins hold slow noise " + std::to_string(widest) +
                            " times the white floor (1/f wander, measured by the baseline test): sigma widened there, "
                            "continued above as 1/f");
    }
    out.band = dsp::band_from_sigma(
        out.result.f_hz, out.result.z_ohm, have ? out.result.z_sigma_ohm : Eigen::VectorXd(),
        opt.coverage_factor,
        est->sigma_source +
            (comp ? " + fixture standards" : ""));
    if (!have)
      out.notes.push_back(
          "uncertainty: the estimate carries no per-point sigma (Prony bootstrap 0?)");
  }

  // The band's random part (circular σ), for the KK thresholds: the model-order
  // part below is a bias allowance, not noise, and must not relax the test.
  Eigen::VectorXd noise_sigma;
  if (out.band) {
    noise_sigma.resize(out.band->size());
    for (Eigen::Index k = 0; k < noise_sigma.size(); ++k)
      noise_sigma[k] =
          std::sqrt(2.0) * std::hypot(out.band->abs_sigma_ohm[k],
                                      out.band->abs_ohm[k] * out.band->phase_sigma_rad[k]);
  }
  // Model-order part (Prony): how much the estimate moves one order step up or down.
  if (out.band && opt.order_spread && order && est->caps.modes) {
    const Eigen::Index n = out.band->size();
    Eigen::VectorXd dl = Eigen::VectorXd::Zero(n), dp = Eigen::VectorXd::Zero(n);
    int used = 0;
    for (long sgn : {-1L, 1L}) {
      const long q = static_cast<long>(*order) + sgn * static_cast<long>(opt.order_spread_step);
      if (q < 1) continue;
      try {
        auto r = estimate(*est, ready, b, o2, static_cast<std::size_t>(q), 0);
        if (zdesk) dsp::deskew_impedance(r, ready.front().r1_ohm, out.skew_applied_s);
        if (comp)
          for (Eigen::Index k = 0; k < n; ++k) r.z_ohm[k] = comp->correct(r.f_hz[k], r.z_ohm[k]);
        for (Eigen::Index k = 0; k < n; ++k) {
          dl[k] = std::max(
              dl[k], std::abs(std::log(std::abs(r.z_ohm[k]) / std::abs(out.result.z_ohm[k]))));
          dp[k] = std::max(dp[k], std::abs(std::arg(r.z_ohm[k] / out.result.z_ohm[k])));
        }
        ++used;
      } catch (const std::invalid_argument&) {
        // the data cannot carry that order: no spread from it
      }
    }
    if (used) {
      for (Eigen::Index k = 0; k < n; ++k) {
        out.band->abs_sigma_ohm[k] =
            std::hypot(out.band->abs_sigma_ohm[k], dl[k] * out.band->abs_ohm[k]);
        out.band->phase_sigma_rad[k] = std::hypot(out.band->phase_sigma_rad[k], dp[k]);
      }
      out.band->source += " + model order (orders " + std::to_string(*order) + " +- " +
                          std::to_string(opt.order_spread_step) + ")";
    }
  }

  // Kramers–Kronig / passivity of the result.
  if (opt.kk) {
    try {
      out.kk =
          dsp::kramers_kronig_check(out.result.f_hz, out.result.z_ohm, noise_sigma, opt.kk_options);
    } catch (const std::invalid_argument& e) {
      out.notes.push_back(std::string("Kramers-Kronig check not run: ") + e.what());
    }
  }
  // Per-shot validity, on the records as recorded.
  if (opt.validity) {
    std::vector<dsp::DividerRecord> v;
    for (const auto& r : ready) v.push_back(r.view());
    dsp::ShotValidityOptions vo = opt.validity_options;
    vo.fmin_hz = b.fmin_hz;
    vo.fmax_hz = b.fmax_hz;
    dsp::PronyImpedanceOptions po = opt.prony;
    po.prony.band_hz = b.fmax_hz;
    po.prony.order = order;
    po.bootstrap = 0;
    out.validity = dsp::check_shots(v, po, vo);
  }
  if (opt.stabilization && est->caps.modes) {
    const OwnedRecord avg = mean_record(views(ready));
    dsp::PronyImpedanceOptions po = o2.prony;
    po.prony.band_hz = b.fmax_hz;
    po.bootstrap = 0;
    dsp::StabilizationOptions so = opt.stabilization_options;
    if (so.fmax_hz <= 0) so.fmax_hz = b.fmax_hz;
    out.stabilization = dsp::stabilization_chart(avg.view(), po, so);
  }
  return out;
}

}  // namespace piezo::acq
