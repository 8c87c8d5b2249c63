// The gap diagnosis on the simulated bench: its data (the shot ensemble)
// against the bench's exact frequency response, and its verdicts against the
// effect the bench injected (read from the test's own SimSpec, never from the
// diagnosis).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "acquisition/divider_record.hpp"
#include "dsp/shot_ensemble.hpp"
#include "model/bench_response.hpp"
#include "model/material_spec.hpp"
#include "model/modal.hpp"
#include "model/tube_model.hpp"
#include "tests/support/sim_capture.hpp"

using namespace piezo;
namespace fs = std::filesystem;

namespace {
fs::path tmp_dir(const std::string& name) {
  fs::path d = fs::path(PIEZO_BINARY_DIR) / "tests-tmp" / name;
  fs::create_directories(d);
  return d;
}

acq::SimSpec target_spec() {
  acq::SimSpec s;
  s.isotropic = true;
  s.set = "YE11=6.66e10,nu12=0.3333,d31=-210e-12,epsT33_rel=2294";
  return s;
}

model::ModalPortModel spec_port(const acq::SimSpec& s) {
  auto mat = model::resolve_material({s.material, s.isotropic, s.set});
  model::TubeGeometry g = s.geometry;
  g.density_kg_m3 = mat.density_kg_m3;
  model::TubeModel tube(g);
  model::ModalSolver solver(tube);
  model::ModalOptions mo;
  mo.n_modes = s.modes;
  return solver.port_model(model::to_e_form(mat.d), mo);
}
}  // namespace

TEST(ShotEnsemble, EqualsTheBenchsExactResponseAndItsNoiseIsMeasured) {
  for (const char* fx : {"", "channel_skew=1e-7"}) {
    auto spec = target_spec();
    spec.noise_rel = 5e-3;
    spec.seed = 5;
    if (*fx) model::apply_effect_assignment(spec.effects, fx);
    auto sim = acq::make_sim_bench(spec, 3140.0);
    for (const auto& plan : {test::seed_lab_plan(8), test::chirp_plan(8)}) {
      auto cap = test::sim_capture(sim, plan, tmp_dir("ensemble") / "c.h5");
      std::vector<dsp::DividerRecord> recs;
      for (const auto& s : cap.shots) recs.push_back(acq::divider_record(cap, s));
      auto e = dsp::impedance_shot_ensemble(recs);
      std::vector<double> f(e.f_hz.data(), e.f_hz.data() + e.f_hz.size());
      auto z = model::bench_impedance(spec_port(spec), spec.damping, spec.effects, 3140.0, f);
      double worst = 0, chi2 = 0;
      for (std::size_t i = 0; i < f.size(); ++i) {
        const auto l = std::log(e.z_ohm[static_cast<Eigen::Index>(i)] / z[i]);
        worst = std::max(worst, std::max(std::fabs(l.real()) / e.sigma_log_mag[static_cast<Eigen::Index>(i)],
                                         std::fabs(l.imag()) / e.sigma_phase[static_cast<Eigen::Index>(i)]));
        chi2 += std::pow(l.real() / e.sigma_log_mag[static_cast<Eigen::Index>(i)], 2) +
                std::pow(l.imag() / e.sigma_phase[static_cast<Eigen::Index>(i)], 2);
      }
      std::printf("%s %s: worst |ln ratio|/sigma %.2f, chi2/N %.2f over %zu\n", fx, std::string(to_string(plan.excitation.kind)).c_str(), worst,
                  chi2 / (2.0 * f.size()), f.size());
      // Unbiased to within its own measured noise: χ²/N near 1, no 5σ point
      // (236 frequencies × 2: a 5σ excursion has probability 3e-4).
      EXPECT_LT(chi2 / (2.0 * f.size()), 1.3);
      EXPECT_LT(worst, 5.0);
    }
  }
}
