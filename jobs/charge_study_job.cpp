// The jobs' room (jobs/): `model charge`, the seed's §5.1 on our FE tube (see charge_study_job.hpp).
#include "jobs/charge_study_job.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <complex>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <span>
#include <string>

#include "dsp/cross_spectra.hpp"
#include "dsp/features.hpp"
#include "dsp/fft.hpp"
#include "dsp/prony_charge.hpp"
#include "dsp/reference_comparison.hpp"
#include "jobs/job_error.hpp"
#include "jobs/report/plot_cairo.hpp"
#include "model/modal.hpp"
#include "model/transient.hpp"

namespace piezo::jobs {

namespace {

using cd = std::complex<double>;
namespace pm = piezo::model;
namespace rp = piezo::jobs::report;

constexpr double kFs = 1e7;                 // 10 MS/s (the seed's)
constexpr std::size_t kRecord = 50000;      // 5 ms
constexpr double kGridHz = kFs / kRecord;   // 200 Hz: the seed's harmonic grid and the record's bins
constexpr double kFmaxHz = 120e3;           // the seed's 0–120 kHz
constexpr double kFminScoreHz = 1e3;        // Z(0) is infinite: scores from 1 kHz
constexpr std::size_t kSeedGap = 26;        // the seed's Fig 27: the gap after the 26th value

// One estimate with its score.
struct Estimate {
  std::string method, rule, label;
  std::size_t samples = 0, records = 1, hankel = 0, order = 0;
  dsp::ImpedanceResult result;
  dsp::TruthComparison score;
};

dsp::FeatureOptions feature_options() {
  dsp::FeatureOptions fo;
  fo.fmin_hz = kFminScoreHz;
  fo.fmax_hz = kFmaxHz;
  return fo;
}

// Z = V/(jω·Q) from bin spectra V, Q of the same length on the 200 Hz grid.
dsp::ImpedanceResult ratio_result(const std::string& method, const std::vector<cd>& vk, const std::vector<cd>& qk,
                                  std::size_t samples) {
  const std::size_t kmax = static_cast<std::size_t>(std::llround(kFmaxHz / kGridHz));
  dsp::ImpedanceResult r;
  r.method = method;
  r.samples_used = samples;
  r.f_hz.resize(static_cast<Eigen::Index>(kmax));
  r.z_ohm.resize(static_cast<Eigen::Index>(kmax));
  for (std::size_t k = 1; k <= kmax; ++k) {
    const double f = static_cast<double>(k) * kGridHz;
    r.f_hz[static_cast<Eigen::Index>(k - 1)] = f;
    r.z_ohm[static_cast<Eigen::Index>(k - 1)] = vk[k] / (cd(0.0, 2.0 * std::numbers::pi * f) * qk[k]);
  }
  r.features = dsp::find_features(r.f_hz, r.z_ohm, Eigen::VectorXd(), feature_options());
  return r;
}

nlohmann::json rel_list(const std::vector<double>& v) {
  auto a = nlohmann::json::array();
  for (double e : v) a.push_back(std::isfinite(e) ? nlohmann::json(e) : nlohmann::json(nullptr));
  return a;
}

void write_figure(const rp::Figure& fig, const std::filesystem::path& file) {
  if (file.extension() == ".png")
    rp::write_png(fig, file);
  else
    rp::write_svg(fig, file);
}

// Population std about the mean (the seed's σs of the clean 5 ms record).
double std_dev(const std::vector<double>& x) {
  long double s = 0, s2 = 0;
  for (double v : x) s += v;
  const long double mean = s / static_cast<long double>(x.size());
  for (double v : x) s2 += (v - mean) * (v - mean);
  return static_cast<double>(std::sqrt(s2 / static_cast<long double>(x.size())));
}

std::vector<double> first_difference(const std::vector<double>& x) {
  std::vector<double> d(x.size());
  for (std::size_t k = 0; k < x.size(); ++k) d[k] = x[k] - (k ? x[k - 1] : 0.0);
  return d;
}

// The estimate's name: its CSV column without "_abs_ohm", and its JSON "name".
std::string name_of(const Estimate& e) {
  if (e.method == "xspec") return "xspec_h1_" + std::to_string(e.records) + "x" + std::to_string(e.samples);
  return e.method + (e.method == "prony" ? "_" + e.rule : "") + "_" + std::to_string(e.samples);
}

const char* colour_of(const Estimate& e) {
  if (e.method == "prony") return e.rule == "largest_drop" ? (e.samples <= 1000 ? "#2ca02c" : "#9467bd") : "#8c564b";
  if (e.method == "xspec") return "#d62728";
  return e.samples >= kRecord ? "#ff7f0e" : e.samples <= 1000 ? "#bcbd22" : "#17becf";
}

// Fig 24: the drive and the charge over the record, and the charge's first 0.3 ms.
rp::Figure signals_figure(const std::vector<double>& v, const std::vector<double>& q,
                          const std::vector<double>* noisy, const std::string& subtitle) {
  rp::Figure fig;
  fig.title = "Seed Fig 24 on the FE tube: the drive voltage and the electrode charge";
  fig.subtitle = subtitle;
  auto series = [](const std::string& label, const std::vector<double>& y, std::size_t n, std::size_t step,
                   double scale, const char* colour) {
    rp::Series s{label};
    for (std::size_t k = 0; k < n; k += step) {
      s.x.push_back(1e3 * static_cast<double>(k) / kFs);
      s.y.push_back(scale * y[k]);
    }
    s.colour = colour;
    return s;
  };
  rp::Panel pv;
  pv.title = "drive v(t) = 500 e^(-0.001 t) V";
  pv.x_label = "t [ms]";
  pv.y_label = "v [V]";
  pv.series.push_back(series("v", v, v.size(), 10, 1.0, "#1f77b4"));
  rp::Panel pq;
  pq.title = "charge q(t), 0-5 ms";
  pq.x_label = "t [ms]";
  pq.y_label = "q [uC]";
  if (noisy) pq.series.push_back(series("noisy record 1", *noisy, noisy->size(), 10, 1e6, "#c7c7c7"));
  pq.series.push_back(series("clean", q, q.size(), 10, 1e6, "#1f77b4"));
  rp::Panel pz;
  pz.title = "charge q(t), the first 0.3 ms";
  pz.x_label = "t [ms]";
  pz.y_label = "q [uC]";
  if (noisy) pz.series.push_back(series("noisy record 1", *noisy, 3000, 1, 1e6, "#c7c7c7"));
  pz.series.push_back(series("clean", q, 3000, 1, 1e6, "#1f77b4"));
  fig.panels = {pv, pq, pz};
  return fig;
}

// Figs 25/26/28/29: |Z| of the truth and the estimates, and their dB error.
rp::Figure impedance_figure(const dsp::ImpedanceTruth& truth, const std::vector<Estimate>& est,
                            const std::string& title, const std::string& subtitle) {
  rp::Figure fig;
  fig.title = title;
  fig.subtitle = subtitle;
  fig.shared_x = true;
  rp::Panel pz, pe;
  pz.y_label = "|Z|";
  pz.y_unit = "Ω";
  pz.y_scale = rp::Scale::Log;
  pe.x_label = "frequency";
  pe.x_unit = "Hz";
  pe.y_label = "error [dB]";
  pe.y_range = std::make_pair(-10.0, 10.0);
  pe.note = "clipped at ±10 dB; shaded: ±1.5 % of each true extremum (not scored)";
  rp::Series t{"harmonic (truth)"};
  t.colour = "#000000";
  t.width = 2.0;
  for (double f = kGridHz; f <= kFmaxHz + 0.5; f += kGridHz) {
    t.x.push_back(f);
    t.y.push_back(std::abs(truth.z(f)));
  }
  pz.series.push_back(t);
  for (const auto& e : est) {
    rp::Series s{e.label}, d{e.label};
    s.colour = d.colour = colour_of(e);
    s.dashed = d.dashed = e.method == "prony" && e.rule != "largest_drop";
    d.listed = false;
    for (Eigen::Index k = 0; k < e.result.f_hz.size(); ++k) {
      const double f = e.result.f_hz[k];
      if (f > kFmaxHz) break;
      s.x.push_back(f);
      s.y.push_back(std::abs(e.result.z_ohm[k]));
      d.x.push_back(f);
      const double db = 20.0 * std::log10(std::abs(e.result.z_ohm[k]) / std::abs(truth.z(f)));
      d.y.push_back(std::clamp(db, -10.0, 10.0));
    }
    pz.series.push_back(std::move(s));
    pe.series.push_back(std::move(d));
  }
  for (const auto* v : {&truth.resonances_hz, &truth.antiresonances_hz})
    for (double f : *v) pe.bands.push_back({f * (1 - truth.peak_exclusion_rel), f * (1 + truth.peak_exclusion_rel)});
  pe.hlines.push_back({0.0});
  fig.panels = {pz, pe};
  return fig;
}

// Fig 27: the first 100 normalised singular values of the seed-rule fit.
rp::Figure singular_figure(const Eigen::VectorXd& sv, std::size_t picked, std::size_t samples, std::size_t hankel,
                           const std::string& subtitle) {
  rp::Figure fig;
  fig.title = "Seed Fig 27 on the FE tube: singular values of the " + std::to_string(hankel) + " x " +
              std::to_string(hankel) + " Hankel matrix, " + std::to_string(samples) + " samples";
  fig.subtitle = subtitle;
  fig.note = "red line: the largest drop among the first 100 (the seed's rule), order " + std::to_string(picked) +
             "; grey line: the seed's own gap, after the 26th";
  rp::Panel p;
  p.x_label = "k";
  p.y_label = "s_k / s_1";
  p.y_scale = rp::Scale::Log;
  rp::Series s{"s_k / s_1"};
  s.points = true;
  for (Eigen::Index k = 0; k < std::min<Eigen::Index>(100, sv.size()); ++k) {
    s.x.push_back(static_cast<double>(k + 1));
    s.y.push_back(sv[k] / sv[0]);
  }
  p.series.push_back(s);
  p.markers.push_back({static_cast<double>(picked) + 0.5, "#d62728", "largest drop: order " + std::to_string(picked)});
  p.markers.push_back({static_cast<double>(kSeedGap) + 0.5, "#7f7f7f", "the seed's gap (26)"});
  fig.panels.push_back(p);
  return fig;
}

}  // namespace

nlohmann::json run_charge_study(const ChargeStudyRequest& request) {
  ChargeStudyRequest a = request;
  if (!(a.noise >= 0.0) || !std::isfinite(a.noise) || a.noise > 10.0)
    throw InputError("--noise " + std::to_string(a.noise) + ": give the noise as σn/σs in 0..10 (the seed: 0.1)");
  const double beta = a.beta_s.value_or(a.noise > 0 ? 1e-7 : 0.0);
  if (!(beta >= 0.0) || !std::isfinite(beta) || beta > 1e-5)
    throw InputError("--rayleigh-beta: give β in 0..1e-5 s (the seed: 0 and 1e-7)");
  if (a.samples.empty()) throw InputError("--samples: give at least one sample count (the seed: 1000,3000)");
  for (std::size_t n : a.samples)
    if (n < 100 || n > kRecord)
      throw InputError("--samples " + std::to_string(n) + ": give counts in 100..50000 (the record is 5 ms at 10 MS/s)");
  std::sort(a.samples.begin(), a.samples.end());
  a.samples.erase(std::unique(a.samples.begin(), a.samples.end()), a.samples.end());
  if (a.hankel < 10) throw InputError("--hankel: give at least 10 rows (the seed: 500)");
  if (a.records < 1 || a.records > 200) throw InputError("--records: give 1..200 (the seed: 20)");
  if (a.modes < 4 || a.modes > 200) throw InputError("--modes: give 4..200 (the simulated bench keeps 24)");
  if (a.plot_format != "svg" && a.plot_format != "png")
    throw InputError("--plot-format " + a.plot_format + ": give svg or png");

  // The tube's port model and the clean charge.
  const ResolvedModel mat = resolve_model(a.model);
  pm::TubeModel tube(a.model.geometry, {a.model.n_radial, a.model.n_axial});
  pm::ModalSolver solver(tube);
  pm::ModalOptions mo;
  mo.n_modes = a.modes;
  const pm::ModalPortModel port = solver.port_model(mat.material, mo);
  const pm::RayleighDamping damping{0.0, beta};
  const dsp::ExponentialDrive drive{500.0, -1e-3};
  std::vector<double> v(kRecord);
  for (std::size_t k = 0; k < kRecord; ++k)
    v[k] = drive.amplitude_v * std::exp(drive.pole_per_s * static_cast<double>(k) / kFs);
  const std::vector<double> q = pm::simulate_charge(port, damping, v, kFs);
  const double q_std = std_dev(q);
  const double sigma = a.noise * q_std;
  // The records: record r's noise from its own stream (seed·1000 + r).
  const std::size_t n_records = a.noise > 0 ? a.records : 1;
  std::vector<std::vector<double>> recs(n_records, q);
  if (sigma > 0)
    for (std::size_t r = 0; r < n_records; ++r) {
      std::mt19937_64 rng(a.seed * 1000 + r);
      std::normal_distribution<double> nd(0.0, sigma);
      for (double& x : recs[r]) x += nd(rng);
    }

  // The truth: the port model's harmonic Z (the seed's stepped harmonic analysis).
  const dsp::ImpedanceTruth truth = dsp::impedance_truth(
      [&port, damping](double f) {
        const double w = 2.0 * std::numbers::pi * f;
        return 1.0 / (cd(0.0, w) * port.charge_per_volt(w, damping));
      },
      kFminScoreHz, kFmaxHz);

  std::vector<Estimate> est;
  Eigen::VectorXd seed_sv;
  std::size_t seed_sv_samples = 0, seed_sv_hankel = 0, seed_sv_order = 0;
  const Eigen::VectorXd grid = dsp::make_grid(kGridHz, kFmaxHz, kGridHz);
  char label[160];
  for (std::size_t n : a.samples) {
    const Eigen::VectorXd y = Eigen::Map<const Eigen::VectorXd>(recs[0].data(), static_cast<Eigen::Index>(n));
    for (const dsp::OrderRule rule : {dsp::OrderRule::LargestDrop, dsp::OrderRule::NoiseFloor}) {
      const bool seed_rule = rule == dsp::OrderRule::LargestDrop;
      dsp::PronyOptions o;
      o.order_rule = rule;
      o.max_order = 100;  // the seed's Fig 27 shows the first 100
      if (seed_rule) {
        o.rows = o.cols = std::min(a.hankel, n / 2);
        o.svd = dsp::SvdMethod::Full;
      }
      Estimate e;
      e.method = "prony";
      e.rule = seed_rule ? "largest_drop" : "noise_floor";
      e.samples = n;
      try {
        const auto m = dsp::fit_prony_charge(y, kFs, drive, o);
        e.result = dsp::impedance_from_charge(m, grid, feature_options());
        e.order = m.fit.order;
        e.hankel = seed_rule ? o.rows : n / 2;
        if (seed_rule && seed_sv.size() == 0) {
          seed_sv = m.fit.singular_values;
          seed_sv_samples = n;
          seed_sv_hankel = o.rows;
          seed_sv_order = m.fit.order;
        }
      } catch (const std::exception& ex) {
        throw std::runtime_error("model charge: Prony-SS on the first " + std::to_string(n) +
                                 " charge samples failed (" + ex.what() + "); try other --samples or --hankel");
      }
      std::snprintf(label, sizeof label, "Prony-SS %s, %zu samples (order %zu)",
                    seed_rule ? "seed rule" : "house rule", n, e.order);
      e.label = label;
      est.push_back(std::move(e));
    }
  }
  // The FFT ratio: the first N samples zero-padded to the record (200 Hz bins), and the whole record.
  {
    dsp::RealFft fft(kRecord);
    std::vector<cd> vk(fft.bins()), qk(fft.bins());
    std::vector<std::size_t> lengths = a.samples;
    if (lengths.back() != kRecord) lengths.push_back(kRecord);
    // First differences (x[−1] = 0: at rest before t = 0), as the house FFT
    // ratio (dsp/fft_ratio.hpp): the drive is nearly a step and the charge ends
    // at C·500 V, so the raw records do not return to zero and their DFT at the
    // record's own bins is that of a truncated step (near zero); the
    // differenced records are an impulse and a transient that has decayed.
    // The ratio V/Q is the same for both.
    const std::vector<double> dv = first_difference(v), dq = first_difference(recs[0]);
    for (std::size_t n : lengths) {
      fft.forward(dv.data(), n, vk.data());
      fft.forward(dq.data(), n, qk.data());
      Estimate e;
      e.method = "fft";
      e.samples = n;
      e.result = ratio_result("fft", vk, qk, n);
      std::snprintf(label, sizeof label, "FFT ratio, %zu samples%s", n, n < kRecord ? " zero-padded" : " (5 ms)");
      e.label = label;
      est.push_back(std::move(e));
    }
  }
  // The averaged cross spectra over the records (noise only: without it every record is the same).
  if (n_records > 1) {
    std::vector<dsp::DividerRecord> dr;
    for (const auto& r : recs) dr.push_back({v, r, kFs, 1.0, 0, {}});
    dsp::CrossSpectraOptions co;
    co.segment = kRecord;
    co.overlap = 0.0;
    co.window = {dsp::WindowKind::Rectangular, 0};  // one transient per record, from t = 0
    co.difference = true;  // as the FFT ratio above
    co.estimator = dsp::SpectralEstimator::H1;
    co.fmax_hz = kFmaxHz + kGridHz / 2;
    const dsp::CrossSpectra cs = dsp::cross_spectra(dr, co);
    Estimate e;
    e.method = "xspec";
    e.samples = kRecord;
    e.records = n_records;
    e.result.method = "xspec-h1";
    e.result.samples_used = kRecord;
    std::vector<double> f;
    std::vector<cd> z;
    for (Eigen::Index k = 0; k < cs.f_hz.size(); ++k)
      if (cs.f_hz[k] > 0 && cs.f_hz[k] <= kFmaxHz + 0.5) {
        f.push_back(cs.f_hz[k]);
        z.push_back(1.0 / (cd(0.0, 2.0 * std::numbers::pi * cs.f_hz[k]) * cs.h1[k]));
      }
    e.result.f_hz = Eigen::Map<const Eigen::VectorXd>(f.data(), static_cast<Eigen::Index>(f.size()));
    e.result.z_ohm = Eigen::Map<const Eigen::VectorXcd>(z.data(), static_cast<Eigen::Index>(z.size()));
    e.result.features = dsp::find_features(e.result.f_hz, e.result.z_ohm, Eigen::VectorXd(), feature_options());
    std::snprintf(label, sizeof label, "cross spectra H1, %zu records of 5 ms", n_records);
    e.label = label;
    est.push_back(std::move(e));
  }
  for (auto& e : est) e.score = dsp::compare_to_truth(truth, e.result);

  // The report.
  nlohmann::json j;
  j["experiment"] = a.noise > 0 ? "seed 5.1.2: noisy charge" : "seed 5.1.1: noise-free charge";
  j["material"] = a.model.material;
  j["model_class"] = mat.model_class;
  j["mesh"] = {{"n_radial", a.model.n_radial}, {"n_axial", a.model.n_axial}};
  j["modes"] = a.modes;
  j["drive"] = {{"amplitude_v", drive.amplitude_v}, {"pole_per_s", drive.pole_per_s}};
  j["sample_rate_hz"] = kFs;
  j["record_samples"] = kRecord;
  j["rayleigh_beta_s"] = beta;
  j["noise"] = {{"level", a.noise}, {"charge_sigma_c", sigma}, {"records", n_records}, {"seed", a.seed}};
  double qmax = 0;
  for (double x : q) qmax = std::max(qmax, std::abs(x));
  j["charge"] = {{"max_abs_c", qmax}, {"std_c", q_std}, {"at_end_c", q.back()}};
  j["truth"] = {{"resonances_hz", truth.resonances_hz},
                {"antiresonances_hz", truth.antiresonances_hz},
                {"abs_z_400hz_ohm", std::abs(truth.z(400.0))},
                {"scored_band_hz", {kFminScoreHz, kFmaxHz}},
                {"peak_exclusion_rel", truth.peak_exclusion_rel}};
  j["estimates"] = nlohmann::json::array();
  for (const auto& e : est) {
    nlohmann::json x = {{"name", name_of(e)},
                        {"method", e.method},
                        {"label", e.label},
                        {"samples", e.samples},
                        {"median_db", e.score.median_db_err},
                        {"max_db", e.score.max_db_err},
                        {"max_db_at_hz", e.score.f_max_db_err},
                        {"scored_points", e.score.scored},
                        {"resonance_err_rel", rel_list(e.score.res_err_rel)},
                        {"antiresonance_err_rel", rel_list(e.score.anti_err_rel)},
                        {"ambiguous_features", e.score.ambiguous}};
    if (e.method == "prony") {
      x["order_rule"] = e.rule;
      x["order"] = e.order;
      x["hankel"] = e.hankel;
    }
    if (e.method == "xspec") x["records"] = e.records;
    j["estimates"].push_back(std::move(x));
  }
  if (seed_sv.size() > 0) {
    nlohmann::json s;
    s["samples"] = seed_sv_samples;
    s["hankel"] = seed_sv_hankel;
    s["largest_drop_order"] = seed_sv_order;
    s["largest_drop_ratio"] = seed_sv[static_cast<Eigen::Index>(seed_sv_order) - 1] /
                              seed_sv[static_cast<Eigen::Index>(seed_sv_order)];
    if (seed_sv.size() > static_cast<Eigen::Index>(kSeedGap))
      s["s26_over_s27"] = seed_sv[kSeedGap - 1] / seed_sv[kSeedGap];
    auto norm = nlohmann::json::array();
    for (Eigen::Index k = 0; k < std::min<Eigen::Index>(100, seed_sv.size()); ++k) norm.push_back(seed_sv[k] / seed_sv[0]);
    s["normalized"] = norm;
    j["singular_values"] = s;
  }

  // Files.
  if (!a.csv.empty()) {
    std::ofstream os(a.csv);
    if (!os) throw InputError("--csv " + a.csv + ": cannot write the file (check the directory and permissions)");
    os << "f_hz,true_abs_ohm";
    for (const auto& e : est) os << ',' << name_of(e) << "_abs_ohm";
    os << '\n';
    char buf[32];
    for (Eigen::Index k = 0; k < grid.size(); ++k) {
      std::snprintf(buf, sizeof buf, "%.10g", grid[k]);
      os << buf;
      std::snprintf(buf, sizeof buf, ",%.10g", std::abs(truth.z(grid[k])));
      os << buf;
      for (const auto& e : est) {
        // Every estimate sits on the 200 Hz grid (Prony evaluated there; the FFT's and the cross spectra's bins).
        const bool on_grid = k < e.result.f_hz.size() && std::abs(e.result.f_hz[k] - grid[k]) < 1e-6;
        std::snprintf(buf, sizeof buf, ",%.10g", on_grid ? std::abs(e.result.z_ohm[k]) : std::nan(""));
        os << buf;
      }
      os << '\n';
    }
    if (!os) throw InputError("--csv " + a.csv + ": writing failed (disk full?)");
    j["csv"] = a.csv;
  }
  if (!a.plot_dir.empty()) {
    const std::filesystem::path dir(a.plot_dir);
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec) throw InputError("--plot-dir " + a.plot_dir + ": cannot create it (" + ec.message() + ")");
    char sub[200];
    std::snprintf(sub, sizeof sub, "500 e^(-0.001 t) V, 10 MS/s, 5 ms; Rayleigh beta %g s; noise %g of std(q)%s", beta,
                  a.noise, n_records > 1 ? (", " + std::to_string(n_records) + " records").c_str() : "");
    const std::string ext = "." + a.plot_format;
    auto files = nlohmann::json::array();
    const auto f24 = dir / ("charge-signals" + ext);
    write_figure(signals_figure(v, q, sigma > 0 ? &recs[0] : nullptr, sub), f24);
    files.push_back(f24.string());
    const auto fz = dir / ("charge-impedance" + ext);
    write_figure(impedance_figure(truth, est,
                                  a.noise > 0 ? "Seed Figs 26, 28, 29 on the FE tube: |Z| from the noisy charge"
                                              : "Seed Fig 25 on the FE tube: |Z| from the noise-free charge",
                                  sub),
                 fz);
    files.push_back(fz.string());
    if (seed_sv.size() > 0) {
      const auto fs = dir / ("charge-singular-values" + ext);
      write_figure(singular_figure(seed_sv, seed_sv_order, seed_sv_samples, seed_sv_hankel, sub), fs);
      files.push_back(fs.string());
    }
    j["plots"] = files;
  }
  return j;
}

}  // namespace piezo::jobs
