// The jobs' room (jobs/): `piezobench impedance` (see impedance_job.hpp).
// Capture → dsp only; no estimator code here.
#include <cmath>
#include "jobs/impedance_job.hpp"

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <ostream>

#include "acquisition/capture_file.hpp"
#include "acquisition/contained_read.hpp"
#include "acquisition/divider_record.hpp"
#include "dsp/deskew.hpp"
#include "dsp/impedance_io.hpp"
#include "dsp/mode_figures.hpp"
#include "dsp/prony_impedance.hpp"
#include "dsp/rayleigh.hpp"
#include "dsp/windows.hpp"
#include "jobs/job_error.hpp"
#include "jobs/json/assessment_json.hpp"
#include "jobs/json/mode_figures_json.hpp"
#include "jobs/pipeline/capture_mode_figures.hpp"
#include "jobs/seed_features.hpp"

namespace piezo::jobs {

namespace {

std::vector<const acq::Shot*> dut_shots(const acq::Capture& cap, bool sine) {
  std::vector<const acq::Shot*> out;
  for (const auto& s : cap.shots)
    if (s.role == acq::Role::Dut && ((s.excitation == acq::Excitation::Sine) == sine)) out.push_back(&s);
  return out;
}

const acq::Shot& pick_shot(const acq::Capture& cap, const ImpedanceRequest& a) {
  if (a.shot) {
    if (*a.shot >= cap.shots.size())
      throw InputError("shot " + std::to_string(*a.shot) + " does not exist (the capture has " +
                       std::to_string(cap.shots.size()) + ")");
    return cap.shots[*a.shot];
  }
  auto d = dut_shots(cap, false);
  for (const auto* s : d)
    if (s->excitation == acq::Excitation::ExpDecay) return *s;
  if (d.empty()) throw InputError("the capture holds no transient \"dut\" shot for method " + a.method);
  return *d.front();
}

nlohmann::json features_json(const dsp::ImpedanceFeatures& f) {
  nlohmann::json j;
  auto list = [](const std::vector<dsp::Feature>& v, bool sigma) {
    nlohmann::json a = nlohmann::json::array();
    for (const auto& x : v) a.push_back(sigma ? x.sigma_hz : x.f_hz);
    return a;
  };
  auto extrema = [](const std::vector<dsp::Feature>& v) {
    nlohmann::json a = nlohmann::json::array();
    for (const auto& x : v) a.push_back(x.extremum_hz);
    return a;
  };
  // resonances_hz: modal (natural) frequencies for Prony, |Z| extrema otherwise.
  j["resonances_zmin_hz"] = extrema(f.resonances);
  j["antiresonances_zmax_hz"] = extrema(f.antiresonances);
  j["resonances_hz"] = list(f.resonances, false);
  j["resonances_sigma_hz"] = list(f.resonances, true);
  j["antiresonances_hz"] = list(f.antiresonances, false);
  j["antiresonances_sigma_hz"] = list(f.antiresonances, true);
  // Significant (issue 41 item 4): a σ that is finite and below a third of
  // the frequency (the feature stands 3σ clear of zero). The text output
  // lists these only; the arrays above keep every candidate, in order.
  auto significant = [](const std::vector<dsp::Feature>& v) {
    nlohmann::json a = nlohmann::json::array();
    for (const auto& x : v) a.push_back(std::isfinite(x.sigma_hz) && x.sigma_hz > 0 && 3.0 * x.sigma_hz < x.f_hz);
    return a;
  };
  j["resonances_significant"] = significant(f.resonances);
  j["antiresonances_significant"] = significant(f.antiresonances);
  j["significance_rule"] = "sigma finite and below a third of the frequency";
  j["capacitance_f"] = f.capacitance_f;
  j["capacitance_sigma_f"] = f.capacitance_sigma_f;
  return j;
}

nlohmann::json result_json(const dsp::ImpedanceResult& r, const std::string& file,
                           const std::vector<std::string>& shots, double fmax) {
  nlohmann::json j;
  j["file"] = file;
  j["shots"] = shots;
  j["method"] = r.method;
  j["samples_used"] = r.samples_used;
  j["features"] = features_json(r.features);
  for (const auto& key : {"resonances_hz", "antiresonances_hz", "capacitance_f"})
    j[key] = j["features"][key];
  if (r.prony) {
    j["order"] = r.prony->order;
    j["order_automatic"] = r.prony->order_automatic;
    j["singular_values_normalized"] = r.prony->singular_values_normalized;
    nlohmann::json poles = nlohmann::json::array();
    std::vector<dsp::PoleInfo> modes;
    for (const auto& p : r.prony->poles) {
      poles.push_back({{"freq_hz", p.freq_hz}, {"damping_ratio", p.damping_ratio},
                       {"re_per_s", p.lambda.real()}, {"im_rad_per_s", p.lambda.imag()}});
      if (p.freq_hz > 0 && p.freq_hz <= fmax && p.damping_ratio > 0) modes.push_back(p);
    }
    j["poles"] = poles;
    if (modes.size() >= 2) {  // eqs 167-169, least squares over the modes in the band
      const auto d = dsp::rayleigh_fit(modes);
      j["rayleigh"] = {{"alpha_per_s", d.alpha}, {"beta_s", d.beta}};
    }
  }
  std::vector<double> re, im;
  for (Eigen::Index k = 0; k < r.z_ohm.size(); ++k) {
    re.push_back(r.z_ohm[k].real());
    im.push_back(r.z_ohm[k].imag());
  }
  j["f_hz"] = std::vector<double>(r.f_hz.data(), r.f_hz.data() + r.f_hz.size());
  j["re_ohm"] = re;
  j["im_ohm"] = im;
  if (r.z_sigma_ohm.size())
    j["sigma_ohm"] = std::vector<double>(r.z_sigma_ohm.data(), r.z_sigma_ohm.data() + r.z_sigma_ohm.size());
  if (r.coherence.size())
    j["coherence"] = std::vector<double>(r.coherence.data(), r.coherence.data() + r.coherence.size());
  return j;
}

// The trust options of the command as assessment options (method, band, estimator options set by the caller).
acq::AssessmentOptions trust_options(const ImpedanceRequest& a) {
  acq::AssessmentOptions o;
  if (a.compensation == "none") {
    o.compensate = false;
  } else if (a.compensation != "auto") {
    const auto m = dsp::parse_fixture_model(a.compensation);
    if (!m) throw InputError("--compensation: unknown model '" + a.compensation + "'");
    o.model = *m;
  }
  o.deskew = !a.no_deskew;
  o.baseline = !a.no_baseline;
  o.baseline_remove = a.remove_baseline;
  if (a.skew_ns) o.skew_s = *a.skew_ns * 1e-9;
  if (a.uncertainty == "auto") o.uncertainty = acq::UncertaintySource::Auto;
  else if (a.uncertainty == "shots") o.uncertainty = acq::UncertaintySource::Shots;
  else if (a.uncertainty == "noise") o.uncertainty = acq::UncertaintySource::Noise;
  else if (a.uncertainty == "none") o.uncertainty = acq::UncertaintySource::None;
  else throw InputError("--uncertainty: expected auto, shots, noise or none, got '" + a.uncertainty + "'");
  o.bootstrap = a.bootstrap_shots;
  o.kk = !a.no_kk;
  o.validity = !a.no_validity;
  o.stabilization = !a.no_stabilization;
  unsigned lo = 0, hi = 0, st = 2;
  char tail = 0;
  const int got = std::sscanf(a.stabilization.c_str(), "%u:%u:%u%c", &lo, &hi, &st, &tail);
  if (got < 2 || got > 3 || lo < 1 || hi < lo || st < 1 || hi > 200)
    throw InputError("--stabilization: expected MIN:MAX[:STEP] orders with 1 <= MIN <= MAX <= 200, got '" +
                     a.stabilization + "'");
  o.stabilization_options.min_order = lo;
  o.stabilization_options.max_order = hi;
  o.stabilization_options.step = st;
  return o;
}

}  // namespace

ImpedanceJobResult run_impedance(const ImpedanceRequest& a) {
  ImpedanceJobResult out;
  out.capture = acq::read_capture_contained(a.file);  // a crash of libhdf5 costs the file only
  const acq::Capture& cap = out.capture;
  if (cap.shots.empty()) throw InputError("the capture holds no shot");
  const auto win = dsp::parse_window(a.window);
  if (!win) throw InputError("unknown window '" + a.window + "'");
  out.trust = trust_options(a);
  acq::AssessmentOptions& trust = out.trust;
  std::vector<std::string>& names = out.shots;
  dsp::ImpedanceResult& r = out.z;
  std::optional<acq::ImpedanceAssessment>& assessed = out.assessed;
  std::optional<dsp::ImpedanceBand>& band = out.band;
  std::optional<acq::CaptureCalibration>& sine_cal = out.sine_cal;
  double& band_hz = out.band_hz;
  band_hz = a.fmax;
  const acq::EstimatorEntry* estimator = acq::builtin_estimators().find(a.method);
  if (!estimator)
    throw InputError("--method: unknown estimator '" + a.method + "' (expected " +
                     acq::join_keys(acq::builtin_estimators().keys()) + ")");
  if (estimator->caps.sine_shots) {
    std::vector<dsp::DividerRecord> records;
    std::vector<double> freqs;
    for (const auto* s : dut_shots(cap, true)) {
      if (!s->frequency_hz) throw InputError("sine shot " + s->name + " has no frequency_hz");
      records.push_back(acq::divider_record(cap, *s));
      freqs.push_back(*s->frequency_hz);
      names.push_back(s->name);
    }
    if (records.empty()) throw InputError("the capture holds no \"dut\" sine shot");
    r = estimator->estimate(acq::EstimateInput{records, freqs, {a.fmin, a.fmax, 0.0}, trust, std::nullopt, std::nullopt});
    // Standards measured with a transient drive apply to a stepped-sine estimate
    // too (steady state: the skew is exactly the phase ramp e^{jωτ}).
    bool transient_standards = false;
    for (const auto& sh : cap.shots)
      transient_standards = transient_standards || (sh.role != acq::Role::Dut && sh.excitation != acq::Excitation::Sine);
    if (trust.compensate && transient_standards) {
      acq::CaptureCalibrationOptions co;
      co.fmax_hz = r.f_hz.maxCoeff();
      co.model = trust.model;
      co.deskew = trust.deskew;
      sine_cal = acq::calibrate_from_capture(cap, co);
    } else if (trust.model && *trust.model != dsp::FixtureModel::None) {
      throw InputError("--compensation " + a.compensation +
                       ": the capture holds no transient calibration shot (stepped-sine standards are not supported)");
    }
    const double skew = sine_cal ? sine_cal->skew_applied_s : (trust.skew_s && trust.deskew ? *trust.skew_s : 0.0);
    if (skew != 0.0) dsp::deskew_impedance(r, cap.setup.divider_r1_ohm, skew);
    if (sine_cal) sine_cal->compensate(r);
    if (r.z_sigma_ohm.size() == r.f_hz.size() && trust.uncertainty != acq::UncertaintySource::None)
      band = dsp::band_from_sigma(r.f_hz, r.z_ohm, r.z_sigma_ohm, trust.coverage_factor,
                                  sine_cal ? estimator->sigma_source + " + fixture standards" : estimator->sigma_source);
  } else {
    const acq::Shot& shot = pick_shot(cap, a);
    const double fs = shot.sample_rate_hz;
    // Unset: the one estimate the pipeline makes (acq::default_estimate); a
    // wider --fmax keeps the default step's 2000 points at most.
    const acq::EstimateDefaults est = acq::default_estimate(shot);
    const double fmax = a.fmax > 0 ? a.fmax : est.fmax_hz;
    band_hz = fmax;
    if (!(fmax <= fs / 2)) throw InputError("--fmax above the Nyquist frequency");
    const double step = a.step > 0 ? a.step : std::max(est.step_hz, fmax / 2000);
    trust.method = a.method;
    trust.fmin_hz = a.fmin > 0 ? a.fmin : step;
    trust.fmax_hz = fmax;
    trust.step_hz = step;
    trust.prony.prep.max_samples = a.samples.value_or(est.max_samples);
    trust.prony.prony.order = a.order;
    trust.prony.bootstrap = a.bootstrap;
    trust.fft.prep.max_samples = a.samples.value_or(0);
    trust.fft.window = {*win, 0.5};
    trust.xspec.segment = a.segment.value_or(0);
    trust.xspec.overlap = a.overlap;
    trust.xspec.window = {*win, 0.5};
    trust.xspec.prep.max_samples = a.samples.value_or(0);
    // prony and fft: one shot unless --average; xspec: every shot of the drive as a segment
    if (!estimator->caps.segments && (!a.average || a.one_shot || a.shot)) trust.shot = static_cast<std::size_t>(&shot - cap.shots.data());
    assessed = acq::assess_impedance(cap, trust);
    r = assessed->result;
    names = assessed->shots;
    band = assessed->band;
    try {
      out.drive = capture_drive_band(cap, names);
    } catch (const std::invalid_argument&) {
      // too short a record to tell its band: every feature stands on its σ alone
    }
  }
  return out;
}

nlohmann::json impedance_json(const ImpedanceRequest& a, const ImpedanceJobResult& res) {
  const acq::Capture& cap = res.capture;
  const dsp::ImpedanceResult& r = res.z;
  const acq::AssessmentOptions& trust = res.trust;
  const auto& assessed = res.assessed;
  const auto& band = res.band;
  const auto& sine_cal = res.sine_cal;
  const double band_hz = res.band_hz;
  auto j = result_json(r, a.file, res.shots, band_hz > 0 ? band_hz : 1e300);
  if (res.drive) {  // features outside the drive's band are not significant (issue 41 item 4)
    const auto& d = *res.drive;
    j["drive_band"] = {{"found", d.found}, {"lo_hz", d.lo_hz}, {"hi_hz", d.hi_hz}, {"note", d.note}};
    auto& fj = j["features"];
    for (const std::string kind : {"resonances", "antiresonances"}) {
      nlohmann::json in = nlohmann::json::array();
      const auto& fs = fj[kind + "_hz"];
      for (std::size_t k = 0; k < fs.size(); ++k) {
        const double f = fs[k].is_number() ? fs[k].get<double>() : 0.0;
        const bool inside = !d.found || (f >= d.lo_hz && f <= d.hi_hz);
        in.push_back(inside);
        if (!inside) fj[kind + "_significant"][k] = false;
      }
      fj[kind + "_in_drive_band"] = in;
    }
    fj["significance_rule"] = "sigma finite and below a third of the frequency, inside the drive's band";
  }
  if (assessed) {
    j.update(jobs::assessment_json(*assessed));  // fields added, none renamed
  } else {  // stepped sine
    const auto model = sine_cal ? sine_cal->model : dsp::FixtureModel::None;
    j["compensation"] = {{"applied", model != dsp::FixtureModel::None},
                         {"model", std::string(dsp::to_string(model))},
                         {"description", dsp::describe(model)}};
    if (sine_cal) j["compensation"]["fixture"] = jobs::fixture_json(sine_cal->fixture);
    const double skew = sine_cal ? sine_cal->skew_applied_s : (trust.skew_s && trust.deskew ? *trust.skew_s : 0.0);
    j["deskew"] = {{"applied", skew != 0.0},
                   {"skew_s", skew},
                   {"skew_ns", skew * 1e9},
                   {"source", sine_cal ? sine_cal->skew_source : (trust.skew_s ? "given (a stored skew)" : "")}};
    j["notes"] = nlohmann::json::array();
    bool sine_standards = false;
    for (const auto& sh : cap.shots)
      sine_standards = sine_standards || (sh.role != acq::Role::Dut && sh.excitation == acq::Excitation::Sine);
    if (sine_standards && !sine_cal)
      j["notes"].push_back("the capture's calibration shots are stepped-sine shots: not supported yet, Z is not compensated");
    if (band)
      j["uncertainty"] = {{"source", band->source}, {"coverage_factor", band->coverage_factor},
                          {"abs_sigma_ohm", std::vector<double>(band->abs_sigma_ohm.data(), band->abs_sigma_ohm.data() + band->size())}};
  }
  return j;
}

// The figures of every mode on the estimate's grid, with the estimator's σ per point
// when it has one; D_mean from the capture's geometry (or the project's default tube).
void add_impedance_mode_figures(nlohmann::json& j, const ImpedanceJobResult& res) {
  const auto m = jobs::capture_mode_figures(res.capture, res.z);
  if (!m.error.empty()) {
    j["modes"] = nlohmann::json::array();
    j["mode_summary"] = {{"notes", {"no mode figures: " + m.error}}};
    return;
  }
  j["modes"] = jobs::modes_json(m.figures);
  j["mode_summary"] = jobs::mode_summary_json(m.figures, m.mean_diameter_m, m.mean_diameter_source);
  j["mode_summary"]["source"] = m.source;
}

void write_impedance_csv(std::ostream& os, const ImpedanceJobResult& r) {
  if (r.band) dsp::write_impedance_csv(os, r.z, *r.band);
  else dsp::write_impedance_csv(os, r.z);
}

void write_impedance_s1p(std::ostream& os, const ImpedanceJobResult& r) { dsp::write_touchstone_s1p(os, r.z); }

}  // namespace piezo::jobs
