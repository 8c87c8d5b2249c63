// Issue 19, item 2: which damping model fits the output-error data better —
// Rayleigh C = βK_UU (mode k damped by jωβκ_k) or complex constants
// cE·(1 + j/Qm) (jκ_k/Qm per mode) — χ²/ν of the fit and of the held-out
// prediction with each:
//  * our own simulated one-shot captures with Rayleigh truth (the time-domain
//    divider simulator, model::simulate_divider) and with complex-constant
//    truth (the frequency-domain divider on the 40-mode port model with
//    MaterialLosses::qm, ModalPortModel::charge_per_volt — a different mode
//    count and code path from the estimator's 16-mode tube_admittance);
//    the held-out capture is a chirp of the same tube with its own noise;
//  * (PIEZO_DAMPING_STUDY, `make validate`) every case of
//    ../shared/corpus/refsim-v1 (fit.h5, held out holdout.h5), whose truth is
//    Rayleigh β.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>

#include <nlohmann/json.hpp>

#include "acquisition/capture_file.hpp"
#include "dsp/fft.hpp"
#include "model/material_presets.hpp"
#include "model/material_spec.hpp"
#include "model/modal.hpp"
#include "model/transient.hpp"
#include "model/tube_model.hpp"
#include "jobs/pipeline/capture_fit.hpp"
#include "update/output_error.hpp"

namespace {
using namespace piezo;
using cd = std::complex<double>;

constexpr double kFs = 10e6, kR1 = 3140.0;
constexpr std::size_t kN = 20000, kPre = 200;

enum class Drive { exp_decay, chirp };

std::vector<double> drive(Drive d) {
  std::vector<double> v1(kN, 0.0);
  for (std::size_t i = kPre; i < kN; ++i) {
    const double t = double(i - kPre) / kFs, tt = double(kN - kPre) / kFs;
    if (d == Drive::exp_decay) {
      v1[i] = std::exp(-3000.0 * t);
    } else {  // linear chirp 5 kHz → 200 kHz over the record, Hann-tapered ends
      const double f0 = 5e3, f1 = 200e3;
      const double ph = 2 * M_PI * (f0 * t + 0.5 * (f1 - f0) * t * t / tt);
      const double taper = std::min(1.0, std::min(t, tt - t) / (0.05 * tt));
      v1[i] = std::sin(ph) * taper;
    }
  }
  return v1;
}

// v2 of the divider from v1 per DFT bin on a 4× zero-padded record: T = 1/(1 + R1·Y).
std::vector<double> divider_frequency_domain(const model::ModalPortModel& port,
                                             const model::MaterialLosses& l,
                                             const std::vector<double>& v1) {
  const std::size_t nfft = dsp::good_fft_size(4 * v1.size());
  dsp::RealFft fft(nfft);
  std::vector<cd> spec(fft.bins());
  fft.forward(v1.data(), v1.size(), spec.data());
  for (std::size_t k = 1; k < spec.size(); ++k) {
    const double w = 2 * M_PI * kFs * double(k) / double(nfft);
    const cd y = cd(0.0, w) * port.charge_per_volt(w, {}, l);
    spec[k] /= 1.0 + kR1 * y;
  }
  std::vector<double> v2(v1.size());
  fft.inverse(spec.data(), v2.data(), v2.size());
  for (auto& x : v2) x /= double(nfft);
  return v2;
}

struct Truth {
  update::TubeParams params;
  update::OeDamping model = update::OeDamping::rayleigh;
  double beta = 0, qm = 0;
};

struct Record {
  std::vector<double> v1, v2;
};

Record simulate(model::ModalSolver& solver, const update::MaterialClass& cls, const Truth& t,
                Drive d, double noise_rel, std::uint64_t seed) {
  Record r;
  r.v1 = drive(d);
  model::ModalOptions mo;
  mo.n_modes = 40;
  const auto port = solver.port_model(cls.e_form(t.params), mo);
  if (t.model == update::OeDamping::rayleigh) {
    model::DividerCircuit c;
    c.r1_ohm = kR1;
    r.v2 = model::simulate_divider(port, {0.0, t.beta}, c, r.v1, kFs);
  } else {
    model::MaterialLosses l;
    l.qm = t.qm;
    r.v2 = divider_frequency_domain(port, l, r.v1);
  }
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> nd;
  auto rms = [](const std::vector<double>& v) {
    double a = 0;
    for (double x : v) a += x * x;
    return std::sqrt(a / double(v.size()));
  };
  const double s1 = noise_rel * rms(r.v1), s2 = noise_rel * rms(r.v2);
  for (auto& x : r.v1) x += s1 * nd(rng);
  for (auto& x : r.v2) x += s2 * nd(rng);
  return r;
}

update::OeData data_of(const Record& r) {
  update::OeData d;
  d.sample_rate_hz = kFs;
  d.circuit.r1_ohm = kR1;
  d.shots.push_back({r.v1, r.v2, kPre});
  return d;
}

// One fit and its held-out prediction with one damping model.
struct Scored {
  double chi2 = NAN, dof = 0, heldout = NAN, heldout_dof = 0;
  double loss = NAN, loss_sigma = NAN;  // β (s) or Qm
  double loss_sigma_stat = NAN;         // its statistical part (noise, Birge-widened)
  bool ok = false;
};

Scored score(model::ModalSolver& solver, const update::MaterialClass& cls,
             const update::TubeParams& nominal, const update::OeData& fit_data,
             const update::OeData& heldout, update::OeDamping dm, update::OeOptions opt = {}) {
  opt.damping = dm;
  const auto r = update::fit_output_error(solver, cls, nominal, fit_data, opt);
  Scored s;
  s.ok = r.ok();
  s.chi2 = r.chi2_per_dof;
  s.dof = std::max(1.0, double(r.residual_samples) - 5.0);
  if (dm == update::OeDamping::complex_constants) {
    s.loss = r.qm;
    s.loss_sigma = r.qm_sigma;
    if (r.parameters.size() > 4)
      s.loss_sigma_stat = r.qm * r.parameters[4].sigma_statistical / r.eta;
  } else {
    s.loss = r.damping.beta;
    s.loss_sigma = r.parameters.size() > 4 ? r.parameters[4].sigma : NAN;
  }
  const auto p = update::predict_output_error(solver, cls, r.updated, r.loss(), r.effect_set,
                                              heldout, r.band_hz, opt, r.covariance_rel);
  s.heldout = p.chi2_per_dof;
  if (std::getenv("PIEZO_DEBUG_DAMPING") && r.parameters.size() > 4)
    std::printf(
        "    [%s] %s %.4g sigma %.3g (statistical %.3g), chi2/dof %.3f, iterations %d, status %s "
        "%s\n",
        update::damping_name(dm), r.parameters[4].name.c_str(), r.parameters[4].value,
        r.parameters[4].sigma, r.parameters[4].sigma_statistical, r.chi2_per_dof, r.iterations,
        r.parameters[4].status.c_str(), r.parameters[4].note.c_str());
  s.heldout_dof = p.dof;
  return s;
}

const char* better(const Scored& r, const Scored& c, bool heldout) {
  const double a = heldout ? r.heldout : r.chi2, b = heldout ? c.heldout : c.chi2;
  return a <= b ? "Rayleigh" : "complex";
}

// '*' after a χ²: that fit did not converge (max iterations).
void print_row(const std::string& name, const std::string& truth, const Scored& r,
               const Scored& c) {
  std::printf(
      "| %-8s | %-22s | %7.3f%s | %7.3f%s | %-8s | %8.3f | %8.3f | %-8s | %.3g +- %.2g | %.4g +- "
      "%.2g |\n",
      name.c_str(), truth.c_str(), r.chi2, r.ok ? "" : "*", c.chi2, c.ok ? "" : "*",
      better(r, c, false), r.heldout, c.heldout, better(r, c, true), r.loss, r.loss_sigma, c.loss,
      c.loss_sigma);
}

void print_header() {
  std::printf(
      "| capture  | truth                  | fit chi2/dof R | fit chi2/dof C | better | held-out R "
      "| "
      "held-out C | better | beta (s) | Qm |\n");
}

class DampingModels : public ::testing::Test {
 protected:
  model::TubeModel tube{model::TubeGeometry{}};
  model::ModalSolver solver{tube};
  update::MaterialClass cls = update::MaterialClass::isotropic();
  update::TubeParams nominal =
      model::isotropic_params(model::resolve_material({"apc850", true, ""}).d);

  // One simulated tube: the fit (exp-decay drive) and the held-out chirp.
  void run_tube(const std::string& name, const Truth& t, double noise, std::uint64_t seed,
                Scored& r, Scored& c) {
    const auto fit_rec = simulate(solver, cls, t, Drive::exp_decay, noise, seed);
    const auto ho_rec = simulate(solver, cls, t, Drive::chirp, noise, seed + 7919);
    const auto fd = data_of(fit_rec), hd = data_of(ho_rec);
    r = score(solver, cls, nominal, fd, hd, update::OeDamping::rayleigh);
    c = score(solver, cls, nominal, fd, hd, update::OeDamping::complex_constants);
    char tr[64];
    if (t.model == update::OeDamping::rayleigh)
      std::snprintf(tr, sizeof tr, "Rayleigh beta %.3g s", t.beta);
    else
      std::snprintf(tr, sizeof tr, "complex Qm %.0f", t.qm);
    print_row(name, tr, r, c);
  }

  // The assertions of the comparison on one simulated tube.
  void check(const Truth& t, const Scored& r, const Scored& c) {
    EXPECT_TRUE(r.ok && c.ok);
    // Δχ² = ν·(χ²/ν difference): with the same number of parameters, the
    // true model's optimum is below the other's whenever the other cannot
    // mimic it; when it can, they differ by noise, O(1). "Not worse": the
    // other model may be better by at most 2 in Δχ² (two sigma of a χ²₁
    // difference is 4; 2 is a one-parameter likelihood-ratio's 84 %).
    // "Better": by more than the significance the estimator uses for an extra
    // parameter (OeOptions::effect_significance, 25 = five sigma).
    const double dchi2_fit = (r.chi2 - c.chi2) * r.dof;               // > 0: complex better
    const double dchi2_ho = (r.heldout - c.heldout) * r.heldout_dof;  // same on the held-out chirp
    if (t.model == update::OeDamping::rayleigh) {
      EXPECT_LT(dchi2_fit, 2.0) << "Rayleigh truth: complex constants fit better";
      EXPECT_LT(dchi2_ho, 2.0) << "Rayleigh truth: complex constants predict better";
    } else {
      EXPECT_GT(dchi2_fit, 25.0)
          << "complex truth: complex constants not clearly better in the fit";
      EXPECT_GT(dchi2_ho, 25.0) << "complex truth: complex constants not clearly better held out";
      // The measured loss: Qm within 3 of its sigmas — the statistical one,
      // as the simulation has no chain errors (the reported sigma adds the
      // chain tolerances' type-B part, OeOptions: with one exp-decay shot the
      // 0.5 % channel-gain tolerance alone moves ln(1/Qm) by ~0.5).
      EXPECT_LE(std::abs(c.loss - t.qm), 3.0 * c.loss_sigma_stat)
          << "Qm " << c.loss << " +- " << c.loss_sigma_stat << " (statistical)";
      std::printf(
          "    Qm %.4g +- %.2g (statistical; %.2g with the chain's type B) against truth %.4g: "
          "%+.2f sigma\n",
          c.loss, c.loss_sigma_stat, c.loss_sigma, t.qm, (c.loss - t.qm) / c.loss_sigma_stat);
    }
  }

  update::TubeParams tube_k(std::mt19937_64& rng) const {
    std::uniform_real_distribution<double> spread(0.9, 1.1);
    update::TubeParams t = nominal;
    t.y_e11 *= spread(rng);
    t.nu12 *= spread(rng);
    t.d31 *= spread(rng);
    t.eps_t33 *= spread(rng);
    return t;
  }
};

#ifndef PIEZO_DAMPING_STUDY
// make test: one tube of each truth, 2 % noise.
TEST_F(DampingModels, EachTruthPrefersItsOwnModelOnOneTube) {
  std::mt19937_64 rng(19);
  print_header();
  Scored r, c;
  Truth tr{tube_k(rng), update::OeDamping::rayleigh, 7e-8, 0};
  run_tube("sim R1", tr, 0.02, 501, r, c);
  check(tr, r, c);
  Truth tc{tube_k(rng), update::OeDamping::complex_constants, 0, 60};
  run_tube("sim C1", tc, 0.02, 502, r, c);
  check(tc, r, c);
}

// The complex-constant fit on two threads gives the same answer to the last
// bit as on one (as OutputErrorSimulated.TwoThreadsGiveTheSameAnswerAsOne for
// Rayleigh), and reports the model, Qm and its sigma.
TEST_F(DampingModels, ComplexFitIsTheSameOnOneAndTwoThreads) {
  std::mt19937_64 rng(23);
  Truth t{tube_k(rng), update::OeDamping::complex_constants, 0, 80};
  const auto rec = simulate(solver, cls, t, Drive::exp_decay, 0.02, 77);
  update::OeOptions o1, o2;
  o1.damping = o2.damping = update::OeDamping::complex_constants;
  o1.threads = 1;
  o2.threads = 2;
  const auto a = update::fit_output_error(solver, cls, nominal, data_of(rec), o1);
  const auto b = update::fit_output_error(solver, cls, nominal, data_of(rec), o2);
  ASSERT_TRUE(a.ok()) << a.message;
  EXPECT_EQ(a.damping_model, update::OeDamping::complex_constants);
  EXPECT_EQ(a.damping.beta, 0.0);
  EXPECT_EQ(a.parameters.at(4).name, "qm_inverse");
  EXPECT_DOUBLE_EQ(a.qm, 1.0 / a.eta);
  EXPECT_GT(a.qm_sigma, 0.0);
  EXPECT_EQ(a.eta, b.eta);
  EXPECT_EQ(a.qm_sigma, b.qm_sigma);
  EXPECT_EQ(a.chi2_per_dof, b.chi2_per_dof);
  EXPECT_EQ(a.updated.y_e11, b.updated.y_e11);
  EXPECT_EQ(a.updated.d31, b.updated.d31);
}
#else
// make validate: four tubes of each truth (1-3 % noise), then the corpus.
TEST_F(DampingModels, SimulatedStudy) {
  std::mt19937_64 rng(20261126);
  std::uniform_real_distribution<double> noise(0.01, 0.03), lbeta(std::log(4e-8), std::log(1.2e-7)),
      lqm(std::log(30.0), std::log(150.0));
  print_header();
  double sum[4] = {0, 0, 0, 0};
  for (int k = 0; k < 8; ++k) {
    Truth t{tube_k(rng), k < 4 ? update::OeDamping::rayleigh : update::OeDamping::complex_constants,
            0, 0};
    const double nr = noise(rng);
    if (t.model == update::OeDamping::rayleigh)
      t.beta = std::exp(lbeta(rng));
    else
      t.qm = std::exp(lqm(rng));
    Scored r, c;
    run_tube((k < 4 ? "sim R" : "sim C") + std::to_string(k % 4 + 1), t, nr,
             600 + static_cast<std::uint64_t>(k), r, c);
    check(t, r, c);
    sum[0] += r.chi2, sum[1] += c.chi2, sum[2] += r.heldout, sum[3] += c.heldout;
  }
}

TEST_F(DampingModels, CorpusStudy) {
  const auto corpus = std::filesystem::path(PIEZO_SOURCE_DIR) / "../shared/corpus/refsim-v1";
  if (!std::filesystem::exists(corpus / "01" / "fit.h5")) GTEST_SKIP() << "no corpus at " << corpus;
  print_header();
  int rayleigh_fit = 0, rayleigh_ho = 0, n = 0, controls = 0;
  double mean[4] = {0, 0, 0, 0};
  for (int k = 1; k <= 20; ++k) {
    char c[8];
    std::snprintf(c, sizeof c, "%02d", k);
    std::ifstream is(corpus / c / "truth.json");
    const auto truth = nlohmann::json::parse(is);
    const std::string effect =
        truth["effect"].is_null() ? "none" : truth["effect"]["name"].get<std::string>();
    const auto cap = acq::read_capture(corpus / c / "fit.h5");
    const auto ho_cap = acq::read_capture(corpus / c / "holdout.h5");
    const auto cm = jobs::capture_model(cap, "apc850", true);
    const auto fd = jobs::capture_oe_data(cap, std::nullopt);
    const auto hd = jobs::capture_oe_data(ho_cap, std::nullopt);
    const auto r = score(*cm.solver, cm.cls, cm.p0, fd, hd, update::OeDamping::rayleigh);
    const auto x = score(*cm.solver, cm.cls, cm.p0, fd, hd, update::OeDamping::complex_constants);
    print_row(c, effect, r, x);
    EXPECT_TRUE(r.ok)
        << c;  // Rayleigh: an estimate from every capture (as test_output_error_corpus)
    if (effect == "none") {
      // The controls: Rayleigh truth and nothing else. Both fits converge and
      // Rayleigh is not worse, in the fit and held out (the simulated study's
      // Δχ² < 2). The cases with an effect are printed, not asserted: there an
      // effect outside both models decides (complex constants do not converge
      // on the two channel-gain cases, chi2/dof 150-330 for either model).
      ++controls;
      EXPECT_TRUE(x.ok) << c;
      EXPECT_LT((r.chi2 - x.chi2) * r.dof, 2.0) << c;
      EXPECT_LT((r.heldout - x.heldout) * r.heldout_dof, 2.0) << c;
    }
    ++n;
    rayleigh_fit += r.chi2 <= x.chi2;
    rayleigh_ho += r.heldout <= x.heldout;
    mean[0] += r.chi2 / 20, mean[1] += x.chi2 / 20, mean[2] += r.heldout / 20,
        mean[3] += x.heldout / 20;
  }
  std::printf(
      "corpus: Rayleigh better in the fit %d/%d, held out %d/%d; mean chi2/dof fit R %.3f C %.3f, "
      "held out R %.3f C %.3f\n",
      rayleigh_fit, n, rayleigh_ho, n, mean[0], mean[1], mean[2], mean[3]);
  EXPECT_EQ(controls, 6);
}
#endif

}  // namespace
