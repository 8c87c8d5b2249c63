// `piezobench impedance CAPTURE.h5 --method prony|fft|xspec|sine ...`: impedance of
// the "dut" shots of a capture by one of the dsp/ estimators, as text, JSON
// (features, Prony order and singular values), CSV (f_hz,re_ohm,im_ohm) or
// Touchstone 1-port (.s1p, Z, RI). Capture → dsp only; no estimator code here.
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>

#include "acquisition/capture_file.hpp"
#include "acquisition/divider_record.hpp"
#include "dsp/cross_spectra.hpp"
#include "dsp/fft_ratio.hpp"
#include "dsp/impedance_io.hpp"
#include "dsp/prony_impedance.hpp"
#include "dsp/rayleigh.hpp"
#include "dsp/stepped_sine.hpp"
#include "ui/cli/cli_common.hpp"

namespace piezo::cli {

namespace {

struct ImpedanceArgs {
  std::string file, method = "prony", window = "rect", output;
  std::optional<std::size_t> shot, samples, order, segment;
  double fmin = 0, fmax = 0, step = 0, overlap = 0.5;
  std::size_t bootstrap = 20;
  bool csv = false, s1p = false;
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

void run(const ImpedanceArgs& a, Context& ctx) {
  if (int(a.csv) + int(a.s1p) + int(ctx.json) > 1) throw InputError("choose one of --json, --csv, --s1p");
  const auto cap = acq::read_capture(a.file);
  if (cap.shots.empty()) throw InputError("the capture holds no shot");
  const auto win = dsp::parse_window(a.window);
  if (!win) throw InputError("unknown window '" + a.window + "'");
  std::vector<std::string> names;
  dsp::ImpedanceResult r;
  double band = a.fmax;
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
  } else {
    const acq::Shot& shot = pick_shot(cap, a);
    const double fs = shot.sample_rate_hz;
    const double fmax = a.fmax > 0 ? a.fmax : fs / 4;
    band = fmax;
    if (!(fmax <= fs / 2)) throw InputError("--fmax above the Nyquist frequency");
    const double step = a.step > 0 ? a.step : fmax / 2000;
    const double fmin = a.fmin > 0 ? a.fmin : step;
    if (a.method == "prony") {
      dsp::PronyImpedanceOptions o;
      o.prep.max_samples = a.samples.value_or(std::min<std::size_t>(
          3000, shot.samples() - static_cast<std::size_t>(std::max<std::int64_t>(0, shot.pretrigger_samples))));
      o.prony.order = a.order;
      o.prony.band_hz = fmax;
      o.features.fmin_hz = fmin;
      o.bootstrap = a.bootstrap;
      r = dsp::impedance_prony(acq::divider_record(cap, shot), dsp::make_grid(fmin, fmax, step), o);
      names.push_back(shot.name);
    } else if (a.method == "fft") {
      dsp::FftRatioOptions o;
      o.prep.max_samples = a.samples.value_or(0);
      o.window = {*win, 0.5};
      o.fmin_hz = fmin;
      o.fmax_hz = fmax;
      r = dsp::impedance_fft(acq::divider_record(cap, shot), o);
      names.push_back(shot.name);
    } else {  // xspec: every transient dut shot of the chosen shot's excitation
      std::vector<dsp::DividerRecord> recs;
      for (const auto* s : dut_shots(cap, false))
        if (s->excitation == shot.excitation) {
          recs.push_back(acq::divider_record(cap, *s));
          names.push_back(s->name);
        }
      dsp::CrossSpectraOptions o;
      o.segment = a.segment.value_or(0);
      o.overlap = a.overlap;
      o.window = {*win, 0.5};
      o.prep.max_samples = a.samples.value_or(0);
      o.fmin_hz = fmin;
      o.fmax_hz = fmax;
      r = dsp::impedance_xspec(recs, o);
    }
  }
  std::ofstream file;
  std::ostream* os = &std::cout;
  if (!a.output.empty()) {
    file.open(a.output);
    if (!file) throw InputError("cannot write " + a.output);
    os = &file;
  }
  if (a.csv) dsp::write_impedance_csv(*os, r);
  else if (a.s1p) dsp::write_touchstone_s1p(*os, r);
  else {
    const auto j = result_json(r, a.file, names, band > 0 ? band : 1e300);
    if (ctx.json) *os << j.dump(2) << std::endl;
    else print_text(j);
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
  cmd->add_flag("--csv", a->csv, "CSV output: f_hz,re_ohm,im_ohm");
  cmd->add_flag("--s1p", a->s1p, "Touchstone 1-port output (Z, RI, normalised to 50 ohm)");
  cmd->add_option("-o,--output", a->output, "Write the output to this file instead of stdout");
  add_json_flag(cmd, ctx);
  cmd->callback([&ctx, a] { ctx.exit_code = run_command(ctx, [&] { run(*a, ctx); }); });
}

}  // namespace piezo::cli
