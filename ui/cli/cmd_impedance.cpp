// `piezobench impedance CAPTURE.h5 --method prony|fft|xspec|sine ...`: impedance of
// the "dut" shots of a capture by one of the dsp/ estimators, as text, JSON
// (features, Prony order and singular values), CSV (f_hz,re_ohm,im_ohm) or
// Touchstone 1-port (.s1p, Z, RI). Capture → dsp only; no estimator code here.
// Prony, FFT and cross spectra go through acq::assess_impedance: fixture
// compensation and deskew from the capture's calibration shots, uncertainty
// band, Kramers-Kronig check, shot validity and the stabilization chart.
// Per-mode figures (dsp/mode_figures.hpp): key "modes" in --json always, the
// table after the impedance with --figures.
#include <iomanip>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>

#include "acquisition/capture_file.hpp"
#include "acquisition/contained_read.hpp"
#include "acquisition/divider_record.hpp"
#include "acquisition/impedance_assessment.hpp"
#include "dsp/deskew.hpp"
#include "dsp/cross_spectra.hpp"
#include "dsp/fft_ratio.hpp"
#include "dsp/impedance_io.hpp"
#include "dsp/mode_figures.hpp"
#include "dsp/prony_impedance.hpp"
#include "dsp/rayleigh.hpp"
#include "dsp/stepped_sine.hpp"
#include "ui/assessment_json.hpp"
#include "ui/capture_mode_figures.hpp"
#include "ui/cli/cli_common.hpp"
#include "ui/json_text.hpp"
#include "ui/mode_figures_json.hpp"

namespace piezo::cli {

namespace {

struct ImpedanceArgs {
  std::string file, method = "prony", window = "rect", output;
  std::optional<std::size_t> shot, samples, order, segment;
  double fmin = 0, fmax = 0, step = 0, overlap = 0.5;
  std::size_t bootstrap = 20;
  bool csv = false, s1p = false, figures = false;
  // Trust (issue 10): compensation, deskew, uncertainty, validity, KK, stabilization.
  std::string compensation = "auto", uncertainty = "auto", stabilization = "2:30:2";
  std::optional<double> skew_ns;
  bool no_deskew = false, average = false, no_kk = false, no_validity = false, no_stabilization = false;
  std::size_t bootstrap_shots = 30;
};

std::vector<const acq::Shot*> dut_shots(const acq::Capture& cap, bool sine) {
  std::vector<const acq::Shot*> out;
  for (const auto& s : cap.shots)
    if (s.role == acq::Role::Dut && ((s.excitation == acq::Excitation::Sine) == sine)) out.push_back(&s);
  return out;
}

const acq::Shot& pick_shot(const acq::Capture& cap, const ImpedanceArgs& a) {
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
acq::AssessmentOptions trust_options(const ImpedanceArgs& a) {
  acq::AssessmentOptions o;
  if (a.compensation == "none") {
    o.compensate = false;
  } else if (a.compensation != "auto") {
    const auto m = dsp::parse_fixture_model(a.compensation);
    if (!m) throw InputError("--compensation: unknown model '" + a.compensation + "'");
    o.model = *m;
  }
  o.deskew = !a.no_deskew;
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

void print_trust(const nlohmann::json& j) {
  const auto& c = j["compensation"];
  std::printf("  fixture model   %s\n", c["description"].get<std::string>().c_str());
  if (c.contains("fixture")) {
    const auto& f = c["fixture"];
    if (f.contains("fixture_capacitance_f"))
      std::printf("  fixture C       %.4g pF (measured, open)\n", f["fixture_capacitance_f"].get<double>() * 1e12);
    if (f.contains("lead_resistance_ohm"))
      std::printf("  lead R          %.4g ohm (measured, short)\n", f["lead_resistance_ohm"].get<double>());
    if (f.contains("r1_error"))
      std::printf("  R1 error        %+.3f %% (measured, load)\n", f["r1_error"].get<double>() * 100);
  }
  const auto& d = j["deskew"];
  if (d["applied"].get<bool>())
    std::printf("  channel skew    %.2f ns removed (%s)\n", d["skew_ns"].get<double>(), d["source"].get<std::string>().c_str());
  if (j.contains("kramers_kronig"))
    std::printf("  Kramers-Kronig  %s (%s)\n", j["kramers_kronig"]["pass"].get<bool>() ? "pass" : "FAIL",
                j["kramers_kronig"]["note"].get<std::string>().c_str());
  if (j.contains("uncertainty"))
    std::printf("  uncertainty     %s, k = %.2f\n", j["uncertainty"]["source"].get<std::string>().c_str(),
                j["uncertainty"]["coverage_factor"].get<double>());
  if (j.contains("validity"))
    for (const auto& s : j["validity"]["shots"])
      if (!s["flags"].empty())
        std::printf("  shot %s       %s\n", s["name"].get<std::string>().c_str(), s["flags"].dump().c_str());
  for (const auto& n : j["notes"]) std::printf("  note: %s\n", n.get<std::string>().c_str());
}

void print_text(const nlohmann::json& j) {
  std::printf("%s  method %s, %zu samples\n", j["file"].get<std::string>().c_str(),
              j["method"].get<std::string>().c_str(), j["samples_used"].get<std::size_t>());
  if (j.contains("order"))
    std::printf("  model order     %zu (%s)\n", j["order"].get<std::size_t>(),
                j["order_automatic"].get<bool>() ? "automatic" : "manual");
  const auto& f = j["features"];
  auto row = [&](const char* name, const char* key, const char* skey) {
    std::printf("  %-15s", name);
    for (std::size_t k = 0; k < f[key].size(); ++k) {
      const double s = f[skey][k].is_number() ? f[skey][k].get<double>() : -1.0;
      if (s >= 0) std::printf(" %.2f±%.2f Hz", f[key][k].get<double>(), s);
      else std::printf(" %.2f Hz", f[key][k].get<double>());
    }
    std::printf("\n");
  };
  row("resonances", "resonances_hz", "resonances_sigma_hz");
  row("antiresonances", "antiresonances_hz", "antiresonances_sigma_hz");
  if (f["capacitance_f"].is_number())
    std::printf("  capacitance     %.5g F\n", f["capacitance_f"].get<double>());
}

// The figures of every mode on the estimate's grid, with the estimator's σ per point
// when it has one; D_mean from the capture's geometry (or the project's default tube).
void add_mode_figures(nlohmann::json& j, const dsp::ImpedanceResult& r, const acq::Capture& cap) {
  const auto m = ui::capture_mode_figures(cap, r);
  if (!m.error.empty()) {
    j["modes"] = nlohmann::json::array();
    j["mode_summary"] = {{"notes", {"no mode figures: " + m.error}}};
    return;
  }
  j["modes"] = ui::modes_json(m.figures);
  j["mode_summary"] = ui::mode_summary_json(m.figures, m.mean_diameter_m, m.mean_diameter_source);
}

void run(const ImpedanceArgs& a, Context& ctx) {
  if (int(a.csv) + int(a.s1p) + int(ctx.json) > 1) throw InputError("choose one of --json, --csv, --s1p");
  const auto cap = acq::read_capture_contained(a.file);  // a crash of libhdf5 costs the file only
  if (cap.shots.empty()) throw InputError("the capture holds no shot");
  const auto win = dsp::parse_window(a.window);
  if (!win) throw InputError("unknown window '" + a.window + "'");
  acq::AssessmentOptions trust = trust_options(a);
  std::vector<std::string> names;
  dsp::ImpedanceResult r;
  std::optional<acq::ImpedanceAssessment> assessed;
  std::optional<dsp::ImpedanceBand> band;
  std::optional<acq::CaptureCalibration> sine_cal;  // stepped sine: compensated here, not by assess_impedance
  double band_hz = a.fmax;
  if (a.method == "sine") {
    std::vector<dsp::SineShot> shots;
    for (const auto* s : dut_shots(cap, true)) {
      if (!s->frequency_hz) throw InputError("sine shot " + s->name + " has no frequency_hz");
      shots.push_back({acq::divider_record(cap, *s), *s->frequency_hz});
      names.push_back(s->name);
    }
    if (shots.empty()) throw InputError("the capture holds no \"dut\" sine shot");
    dsp::SteppedSineOptions o;
    o.features.fmin_hz = a.fmin;
    if (a.fmax > 0) o.features.fmax_hz = a.fmax;
    r = dsp::impedance_stepped_sine(shots, o);
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
                                  sine_cal ? "lock-in fit covariance + fixture standards" : "lock-in fit covariance");
  } else {
    const acq::Shot& shot = pick_shot(cap, a);
    const double fs = shot.sample_rate_hz;
    const double fmax = a.fmax > 0 ? a.fmax : fs / 4;
    band_hz = fmax;
    if (!(fmax <= fs / 2)) throw InputError("--fmax above the Nyquist frequency");
    const double step = a.step > 0 ? a.step : fmax / 2000;
    trust.method = a.method;
    trust.fmin_hz = a.fmin > 0 ? a.fmin : step;
    trust.fmax_hz = fmax;
    trust.step_hz = step;
    const std::size_t post = shot.samples() - static_cast<std::size_t>(std::max<std::int64_t>(0, shot.pretrigger_samples));
    trust.prony.prep.max_samples = a.samples.value_or(std::min<std::size_t>(3000, post));
    trust.prony.prony.order = a.order;
    trust.prony.bootstrap = a.bootstrap;
    trust.fft.prep.max_samples = a.samples.value_or(0);
    trust.fft.window = {*win, 0.5};
    trust.xspec.segment = a.segment.value_or(0);
    trust.xspec.overlap = a.overlap;
    trust.xspec.window = {*win, 0.5};
    trust.xspec.prep.max_samples = a.samples.value_or(0);
    // prony and fft: one shot unless --average; xspec: every shot of the drive as a segment
    if (a.method != "xspec" && !a.average) trust.shot = static_cast<std::size_t>(&shot - cap.shots.data());
    assessed = acq::assess_impedance(cap, trust);
    r = assessed->result;
    names = assessed->shots;
    band = assessed->band;
  }
  std::ofstream file;
  std::ostream* os = &std::cout;
  if (!a.output.empty()) {
    file.open(a.output);
    if (!file) throw InputError("cannot write " + a.output);
    os = &file;
  }
  if (a.csv) {
    if (band) dsp::write_impedance_csv(*os, r, *band);
    else dsp::write_impedance_csv(*os, r);
  } else if (a.s1p) {
    dsp::write_touchstone_s1p(*os, r);
  } else {
    auto j = result_json(r, a.file, names, band_hz > 0 ? band_hz : 1e300);
    if (assessed) {
      j.update(ui::assessment_json(*assessed));  // fields added, none renamed
    } else {  // stepped sine
      const auto model = sine_cal ? sine_cal->model : dsp::FixtureModel::None;
      j["compensation"] = {{"applied", model != dsp::FixtureModel::None},
                           {"model", std::string(dsp::to_string(model))},
                           {"description", dsp::describe(model)}};
      if (sine_cal) j["compensation"]["fixture"] = ui::fixture_json(sine_cal->fixture);
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
    if (ctx.json || a.figures) add_mode_figures(j, r, cap);
    if (ctx.json) {
      ui::write_json(*os, j);  // streamed, no serialised copy
      *os << std::endl;
    } else {
      print_text(j);
      print_trust(j);
      if (a.figures) ui::print_mode_figures(stdout, j["modes"], j["mode_summary"]);
    }
  }
}

}  // namespace

void register_impedance_command(CLI::App& app, Context& ctx) {
  auto a = std::make_shared<ImpedanceArgs>();
  auto* cmd = app.add_subcommand("impedance", "Impedance of a capture's dut shots (Prony-SS, FFT, cross spectra, stepped sine)");
  cmd->add_option("CAPTURE", a->file, "Capture file (.h5)")->required();
  cmd->add_option("--method", a->method, "prony | fft | xspec | sine")
      ->check(CLI::IsMember({"prony", "fft", "xspec", "sine"}));
  cmd->add_option("--shot", a->shot, "Shot index (prony, fft); default: first dut exp_decay shot");
  cmd->add_option("--samples", a->samples, "Samples after t = 0 (prony: default 3000; fft/xspec: all)");
  cmd->add_option("--order", a->order, "Prony model order (default: automatic)")->check(CLI::PositiveNumber);
  cmd->add_option("--fmin", a->fmin, "Lowest frequency [Hz] (default: one step)");
  cmd->add_option("--fmax", a->fmax, "Highest frequency [Hz] (default: fs/4)");
  cmd->add_option("--step", a->step, "Prony grid step [Hz] (default: fmax/2000)");
  cmd->add_option("--window", a->window, "fft/xspec window: rect, hann, hamming, blackman-harris, flattop, tukey");
  cmd->add_option("--segment", a->segment, "xspec segment length (default: the shortest shot)");
  cmd->add_option("--overlap", a->overlap, "xspec segment overlap fraction")->check(CLI::Range(0.0, 0.95));
  cmd->add_option("--bootstrap", a->bootstrap, "Prony: bootstrap refits for the feature uncertainties");
  cmd->add_flag("--csv", a->csv, "CSV output: f_hz,re_ohm,im_ohm, then the uncertainty band columns");
  cmd->add_option("--compensation", a->compensation,
                  "Fixture compensation from the capture's open/short/load shots: auto | none | open | short | "
                  "open-short | open-short-load")
      ->capture_default_str();
  cmd->add_flag("--no-deskew", a->no_deskew, "Do not estimate/remove the channel-2 skew");
  cmd->add_option("--skew-ns", a->skew_ns, "A stored channel-2 skew (ns, > 0: v2 late) for a capture without calibration shots");
  cmd->add_flag("--average", a->average, "prony/fft: average every dut shot of the drive (default: one shot)");
  cmd->add_option("--uncertainty", a->uncertainty, "Uncertainty band: auto | shots | noise | none")->capture_default_str();
  cmd->add_option("--bootstrap-shots", a->bootstrap_shots, "Replicates of the bootstrap over shots")->capture_default_str();
  cmd->add_flag("--no-kk", a->no_kk, "Skip the Kramers-Kronig / passivity check");
  cmd->add_flag("--no-validity", a->no_validity, "Skip the per-shot validity flags");
  cmd->add_option("--stabilization", a->stabilization, "Prony stabilization chart orders MIN:MAX[:STEP]")->capture_default_str();
  cmd->add_flag("--no-stabilization", a->no_stabilization, "Skip the stabilization chart");
  cmd->add_flag("--figures", a->figures,
                "Per-mode figures after the impedance: fs, fp, k_eff, Qm two ways, BVD R1 L1 C1 C0 "
                "(always under \"modes\" in --json)");
  cmd->add_flag("--s1p", a->s1p, "Touchstone 1-port output (Z, RI, normalised to 50 ohm)");
  cmd->add_option("-o,--output", a->output, "Write the output to this file instead of stdout");
  add_json_flag(cmd, ctx);
  cmd->callback([&ctx, a] { ctx.exit_code = run_command(ctx, [&] { run(*a, ctx); }); });
}

}  // namespace piezo::cli
