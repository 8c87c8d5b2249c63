#include "tests/e2e/e2e_study.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>

#include "acquisition/capture_file.hpp"
#include "acquisition/runner.hpp"
#include "acquisition/sim_setup.hpp"
#include "dsp/prony_impedance.hpp"
#include "model/material_presets.hpp"
#include "model/transient.hpp"
#include "update/least_squares.hpp"
#include "update/port_fit.hpp"
#include "update/updater.hpp"

namespace piezo::test {

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

update::TubeParams apc850_iso() {
  return model::isotropic_params(model::find_preset("apc850").material);
}

void score(E2eMethodResult& m, const update::TubeParams& truth) {
  m.err[0] = m.params.y_e11 / truth.y_e11 - 1.0;
  m.err[1] = m.params.nu12 / truth.nu12 - 1.0;
  m.err[2] = m.params.d31 / truth.d31 - 1.0;
  m.err[3] = m.params.eps_t33 / truth.eps_t33 - 1.0;
}

// Sample-by-sample average of the transient "dut" shots of one drive (as the
// pipeline's estimate stage does: white noise drops by √N).
dsp::DividerRecord averaged_record(const acq::Capture& cap, std::vector<double>& v1,
                                   std::vector<double>& v2, int& averaged) {
  const acq::Shot* first = nullptr;
  averaged = 0;
  for (const auto& s : cap.shots) {
    if (s.role != acq::Role::Dut || s.excitation == acq::Excitation::Sine) continue;
    if (!first) {
      first = &s;
      v1.assign(s.samples(), 0.0);
      v2.assign(s.samples(), 0.0);
    }
    if (s.samples() != first->samples() || s.excitation != first->excitation ||
        s.decay_per_s != first->decay_per_s)
      continue;
    for (std::size_t i = 0; i < v1.size(); ++i) {
      v1[i] += s.v1[i];
      v2[i] += s.v2[i];
    }
    ++averaged;
  }
  if (!first) throw std::invalid_argument("capture holds no transient dut shot");
  for (std::size_t i = 0; i < v1.size(); ++i) {
    v1[i] /= averaged;
    v2[i] /= averaged;
  }
  return {v1,
          v2,
          first->sample_rate_hz,
          cap.setup.divider_r1_ohm,
          static_cast<std::size_t>(std::max<std::int64_t>(0, first->pretrigger_samples)),
          first->daq_range_v};
}

}  // namespace

double E2eMethodResult::max_abs_err() const {
  double m = 0;
  for (double e : err) m = std::max(m, std::abs(e));
  return m;
}

acq::MeasurementPlan seed_lab_plan(int shots) {
  acq::MeasurementPlan p;
  p.excitation.kind = acq::Excitation::ExpDecay;
  p.excitation.amplitude_v = 1.0;
  p.excitation.decay_per_s = 3000.0;
  p.sample_rate_hz = 1e7;
  p.samples = 20000;
  p.pretrigger_samples = 200;
  p.shots = shots;
  p.setup.divider_r1_ohm = 3140.0;
  return p;
}

E2eChain issue6_chain() {
  E2eChain c;
  c.noise_rel = 0.03;
  c.plan = seed_lab_plan(16);
  c.plan.excitation.decay_per_s = 1e5;
  c.prony_samples = 6000;
  c.port_fit = true;
  c.lm_weighted = true;
  return c;
}

E2eChain seed_chain() {
  E2eChain c = issue6_chain();
  c.plan = seed_lab_plan(16);
  c.port_fit = false;
  return c;
}

std::vector<E2eCase> draw_cases(int n, std::uint64_t seed, double spread) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(1.0 - spread, 1.0 + spread);
  const auto p0 = apc850_iso();
  std::vector<E2eCase> out;
  for (int k = 0; k < n; ++k) {
    E2eCase c;
    c.truth.y_e11 = p0.y_e11 * u(rng);
    c.truth.nu12 = p0.nu12 * u(rng);
    c.truth.d31 = p0.d31 * u(rng);
    c.truth.eps_t33 = p0.eps_t33 * u(rng);
    c.noise_seed = seed * 1000 + static_cast<std::uint64_t>(k) + 1;
    out.push_back(c);
  }
  return out;
}

E2eOutcome run_e2e_case(const E2eCase& c, const E2eChain& chain,
                        const std::filesystem::path& work_dir, model::TubeModel& tube,
                        model::ModalSolver& solver) {
  E2eOutcome o;
  o.c = c;
  const auto cls = update::MaterialClass::isotropic();
  const update::TubeParams p0 = apc850_iso();
  model::ModalOptions mo = update::CmcmOptions{}.modal;
  {  // Scoring only: the FE features of the true tube.
    const auto m = cls.e_form(c.truth);
    const auto f = update::model_frequencies(solver, m, 3, 3, mo);
    o.true_resonances_hz = f.resonances_hz;
    o.true_antiresonances_hz = f.antiresonances_hz;
    o.true_capacitance_f = update::model_capacitance(solver, m, 400.0, mo);
  }

  // 1. Capture on the simulated bench (runner → HDF5 → reader).
  auto t0 = Clock::now();
  acq::Capture cap;
  try {
    acq::SimSpec spec;
    spec.material = "apc850";
    spec.isotropic = true;
    char set[256];
    std::snprintf(set, sizeof set, "YE11=%.17g,nu12=%.17g,d31=%.17g,epsT33=%.17g", c.truth.y_e11,
                  c.truth.nu12, c.truth.d31, c.truth.eps_t33);
    spec.set = set;
    spec.damping = chain.damping;
    spec.noise_rel = chain.noise_rel;
    spec.seed = c.noise_seed;
    auto sim = acq::make_sim_bench(spec, chain.plan.setup.divider_r1_ohm);
    acq::Bench bench = acq::open_bench({"sim", std::nullopt}, sim);
    acq::RunnerOptions ro;
    ro.overwrite = true;
    std::filesystem::create_directories(work_dir);
    const auto path = work_dir / "e2e_case.h5";
    acq::run_measurement(bench, chain.plan, path, ro);
    cap = acq::read_capture(path);
  } catch (const std::exception& e) {
    o.failure = std::string("capture: ") + e.what();
    return o;
  }
  o.seconds_capture = since(t0);

  // 2. Z(ω) by Prony-SS on the averaged shots, features.
  t0 = Clock::now();
  try {
    std::vector<double> v1, v2;
    int averaged = 0;
    const dsp::DividerRecord rec = averaged_record(cap, v1, v2, averaged);
    dsp::PronyImpedanceOptions po;
    const std::size_t post = rec.v1.size() - rec.pretrigger_samples;
    po.prep.max_samples = chain.prony_samples > 0 ? std::min(chain.prony_samples, post) : 0;
    po.prony.band_hz = chain.band_hz;
    po.features.fmin_hz = 100.0;
    const auto z = dsp::impedance_prony(rec, dsp::make_grid(100.0, chain.band_hz, 100.0), po);
    o.prony_order = z.prony ? static_cast<int>(z.prony->order) : 0;
    auto& f = o.features;
    const auto& fr = z.features.resonances;
    const auto& fa = z.features.antiresonances;
    // As the pipeline's update stage: the first three of each, |Z| at 400 Hz.
    for (std::size_t k = 0; k < std::min<std::size_t>(3, fr.size()); ++k)
      f.resonances_hz.push_back(fr[k].f_hz);
    for (std::size_t k = 0; k < std::min<std::size_t>(3, fa.size()); ++k)
      f.antiresonances_hz.push_back(fa[k].f_hz);
    if (!(z.features.capacitance_f > 0)) throw std::runtime_error("no low-frequency capacitance");
    f.low_z_hz = 400.0;
    f.low_z_ohm = 1.0 / (2 * M_PI * f.low_z_hz * z.features.capacitance_f);
    if (chain.port_fit) {
      // DAQ offsets from the pretrigger, then the samples from t = 0.
      const std::size_t pre = rec.pretrigger_samples;
      double m1 = 0, m2 = 0;
      if (pre >= 16) {
        for (std::size_t i = 0; i < pre; ++i) {
          m1 += rec.v1[i] / static_cast<double>(pre);
          m2 += rec.v2[i] / static_cast<double>(pre);
        }
      }
      const std::size_t nfit = chain.prony_samples > 0 ? std::min(chain.prony_samples, post) : post;
      const std::size_t lead = pre > 0 ? 1 : 0;  // as jobs/pipeline/estimate_stage.cpp: from the idle sample before t = 0
      std::vector<double> a(nfit), b(nfit);
      for (std::size_t i = 0; i < nfit; ++i) {
        a[i] = rec.v1[pre - lead + i] - m1;
        b[i] = rec.v2[pre - lead + i] - m2;
      }
      update::PortFitStart st;
      st.resonances_hz = f.resonances_hz;
      st.antiresonances_hz = f.antiresonances_hz;
      for (std::size_t k = 0; k < f.resonances_hz.size(); ++k)
        st.damping_ratios.push_back(fr[k].damping_ratio);
      st.capacitance_f = z.features.capacitance_f;
      const auto pf = update::fit_port_model(a, b, rec.sample_rate_hz, rec.r1_ohm, st);
      o.port_fit_note =
          (pf.converged ? "converged in " : "NOT converged (" + pf.message + ") after ") +
          std::to_string(pf.iterations) + " iterations";
      if (!pf.converged) throw std::runtime_error("port fit: " + pf.message);
      f = pf.features;
    }
    f.validate();
  } catch (const std::exception& e) {
    o.failure = std::string("estimate: ") + e.what();
    return o;
  }
  o.seconds_estimate = since(t0);

  // 3. Update, both methods, from APC850's isotropic values.
  try {
    update::UpdateOptions uo;  // as the pipeline's update stage
    uo.max_sweeps = 40;
    uo.sweep_tolerance = 1e-6;
    t0 = Clock::now();
    const auto r = update::update_cmcm(tube, solver, cls, p0, o.features, uo);
    o.cmcm.seconds = since(t0);
    o.cmcm.ok = r.ok();
    o.cmcm.message = r.message;
    o.cmcm.params = r.updated;
    score(o.cmcm, c.truth);
  } catch (const std::exception& e) {
    o.cmcm.message = e.what();
  }
  try {
    update::MeasuredFeatures lf = o.features;
    if (!chain.lm_weighted) {
      lf.resonance_sigma_hz.clear();
      lf.antiresonance_sigma_hz.clear();
      lf.low_z_sigma_ohm = 0;
    }
    t0 = Clock::now();
    const auto l = update::update_lm(tube, solver, cls, p0, lf);
    o.lm.seconds = since(t0);
    o.lm.ok = l.ok();
    o.lm.message = l.message;
    o.lm.params = l.updated;
    score(o.lm, c.truth);
  } catch (const std::exception& e) {
    o.lm.message = e.what();
  }
  return o;
}

E2eCrb e2e_crb(const update::TubeParams& truth, const E2eChain& chain, model::ModalSolver& solver) {
  const auto cls = update::MaterialClass::isotropic();
  const auto& plan = chain.plan;
  const std::size_t post = plan.samples - plan.pretrigger_samples;
  std::vector<double> v1 = acq::synthesize(plan.excitation, plan.sample_rate_hz, post);
  for (double& x : v1) x *= plan.excitation.amplitude_v;
  model::ModalOptions mo;
  mo.n_modes = acq::SimSpec{}.modes;
  model::DividerCircuit circuit;
  circuit.r1_ohm = plan.setup.divider_r1_ohm;
  // x = (ln YE11, ln nu12, ln|d31|, ln εT33, β/β0, α/α_ref).
  const double beta0 = chain.damping.beta > 0 ? chain.damping.beta : 1e-7, alpha_ref = 100.0;
  auto v2_of = [&](const Eigen::Matrix<double, 6, 1>& x) {
    update::TubeParams p = truth;
    p.y_e11 *= std::exp(x[0]);
    p.nu12 *= std::exp(x[1]);
    p.d31 *= std::exp(x[2]);
    p.eps_t33 *= std::exp(x[3]);
    const auto port = solver.port_model(cls.e_form(p), mo);
    const model::RayleighDamping d{chain.damping.alpha + alpha_ref * x[5],
                                   chain.damping.beta + beta0 * x[4]};
    const auto v2 = model::simulate_divider(port, d, circuit, v1, plan.sample_rate_hz);
    const std::size_t n = chain.prony_samples > 0 ? std::min(chain.prony_samples, post) : post;
    return Eigen::VectorXd(
        Eigen::Map<const Eigen::VectorXd>(v2.data(), static_cast<Eigen::Index>(n)));
  };
  Eigen::Matrix<double, 6, 1> x0 = Eigen::Matrix<double, 6, 1>::Zero();
  const Eigen::VectorXd v20 = v2_of(x0);
  // Noise of the averaged record as the simulated DAQ sets it (std over the whole record).
  {
    const auto full = model::simulate_divider(solver.port_model(cls.e_form(truth), mo),
                                              chain.damping, circuit, v1, plan.sample_rate_hz);
    double mean = 0, var = 0;
    const double n = static_cast<double>(plan.samples);  // pretrigger samples are 0
    for (double x : full) mean += x / n;
    for (double x : full) var += (x - mean) * (x - mean);
    var += static_cast<double>(plan.pretrigger_samples) * mean * mean;
    E2eCrb out;
    out.noise_v2_v =
        chain.noise_rel * std::sqrt(var / n) / std::sqrt(static_cast<double>(plan.shots));
    Eigen::MatrixXd g(v20.size(), 6);
    for (int k = 0; k < 6; ++k) {
      const double h = k < 4 ? 1e-5 : 1e-3;
      Eigen::Matrix<double, 6, 1> xp = x0, xm = x0;
      xp[k] += h;
      if (k == 5) {  // α ≥ 0: forward difference at α = 0
        g.col(k) = (v2_of(xp) - v20) / h;
      } else {
        xm[k] -= h;
        g.col(k) = (v2_of(xp) - v2_of(xm)) / (2 * h);
      }
    }
    const Eigen::MatrixXd fisher = g.transpose() * g / (out.noise_v2_v * out.noise_v2_v);
    const Eigen::MatrixXd cov = fisher.inverse();
    for (int k = 0; k < 4; ++k) out.sigma[k] = std::sqrt(cov(k, k));  // d ln p = relative
    return out;
  }
}

std::string e2e_header() {
  return "case | true YE11 (GPa) | nu12 | d31 (pC/N) | epsT33/eps0 || CMCM err % YE11 nu12 d31 "
         "epsT33 | "
         "t (s) || LM err % YE11 nu12 d31 epsT33 | t (s) || feature err % (res 1-3 | anti 1-3)";
}

std::string e2e_row(int index, const E2eOutcome& o) {
  char buf[640];
  const auto& t = o.c.truth;
  int n = std::snprintf(buf, sizeof buf, "%2d | %.3f | %.4f | %.2f | %.0f || ", index,
                        t.y_e11 * 1e-9, t.nu12, t.d31 * 1e12, t.eps_t33 / model::kEps0);
  std::string s(buf, static_cast<std::size_t>(n));
  if (!o.failure.empty()) return s + "chain failed: " + o.failure;
  auto method = [&](const E2eMethodResult& m) {
    char b[200];
    if (!m.ok && m.message.size() && m.params.y_e11 == 0) {
      std::snprintf(b, sizeof b, "failed: %.60s | - ", m.message.c_str());
      return std::string(b);
    }
    std::snprintf(b, sizeof b, "%+.3f %+.3f %+.3f %+.3f%s | %.2f ", 100 * m.err[0], 100 * m.err[1],
                  100 * m.err[2], 100 * m.err[3], m.ok ? "" : " (not converged)", m.seconds);
    return std::string(b);
  };
  s += method(o.cmcm) + "|| " + method(o.lm) + "|| ";
  auto rel = [](const std::vector<double>& a, const std::vector<double>& b) {
    std::string r;
    for (std::size_t k = 0; k < a.size(); ++k) {
      char x[32];
      if (k < b.size())
        std::snprintf(x, sizeof x, "%+.3f ", 100 * (a[k] / b[k] - 1));
      else
        std::snprintf(x, sizeof x, "? ");
      r += x;
    }
    return r;
  };
  s += rel(o.features.resonances_hz, o.true_resonances_hz) + "| " +
       rel(o.features.antiresonances_hz, o.true_antiresonances_hz);
  return s;
}

}  // namespace piezo::test
