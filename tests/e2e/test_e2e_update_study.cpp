// Issue 6 acceptance (make validate): "End to end on the simulated bench (3 %
// noise, true parameters drawn within ±15 % of APC850 in the isotropic class,
// Rayleigh damping): capture → Prony → update recovers the four parameters
// (YE11, nu12, d31, εT33) within 1 % in at least 19 of 20 random cases; the LM
// updater's results and run times beside CMCM's." Prints the table, the
// Cramér–Rao bound of each case and, for the record, the seed's chain
// (exp_decay at 3000 1/s, Prony features only) and the variants between the two
// on the same tubes; the seed's drive with 64 shots meets the acceptance too.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>

#include "model/modal.hpp"
#include "model/tube_model.hpp"
#include "tests/e2e/e2e_study.hpp"

using namespace piezo;

namespace {

std::filesystem::path work_dir() {
  return std::filesystem::temp_directory_path() /
         ("piezobench-e2e-study-" + std::to_string(::getpid()));
}

struct Tally {
  int cmcm = 0, lm = 0, lm_values = 0;  // lm_values: within 1 % whatever the status
};

Tally run_study(const test::E2eChain& chain, const char* title, bool crb) {
  model::TubeModel tube(model::TubeGeometry{});
  model::ModalSolver solver(tube);
  const auto cases = test::draw_cases(20, 6);
  std::printf("\n== %s ==\n%s%s\n", title, test::e2e_header().c_str(),
              crb ? " || CRB 1σ % YE11 nu12 d31 epsT33" : "");
  Tally t;
  double worst_crb[4] = {0, 0, 0, 0};
  for (int i = 0; i < 20; ++i) {
    const auto o = test::run_e2e_case(cases[i], chain, work_dir(), tube, solver);
    std::string row = test::e2e_row(i + 1, o);
    if (crb) {
      const auto b = test::e2e_crb(cases[i].truth, chain, solver);
      char buf[96];
      std::snprintf(buf, sizeof buf, " || %.3f %.3f %.3f %.3f", 100 * b.sigma[0], 100 * b.sigma[1],
                    100 * b.sigma[2], 100 * b.sigma[3]);
      row += buf;
      for (int k = 0; k < 4; ++k) worst_crb[k] = std::max(worst_crb[k], b.sigma[k]);
    }
    std::printf("%s\n", row.c_str());
    if (!o.cmcm.ok && o.failure.empty()) std::printf("     CMCM: %s\n", o.cmcm.message.c_str());
    if (!o.lm.ok && o.failure.empty()) std::printf("     LM: %s\n", o.lm.message.c_str());
    if (!o.failure.empty()) continue;
    t.cmcm += o.cmcm.ok && o.cmcm.max_abs_err() < 0.01;
    t.lm += o.lm.ok && o.lm.max_abs_err() < 0.01;
    t.lm_values += o.lm.max_abs_err() < 0.01;
  }
  std::printf("%s: within 1 %% and converged: CMCM %d/20, LM %d/20 (LM values alone %d/20)\n",
              title, t.cmcm, t.lm, t.lm_values);
  if (crb)
    std::printf(
        "largest CRB 1σ over the 20 tubes: YE11 %.3f %%, nu12 %.3f %%, d31 %.3f %%, epsT33 %.3f "
        "%%\n",
        100 * worst_crb[0], 100 * worst_crb[1], 100 * worst_crb[2], 100 * worst_crb[3]);
  std::filesystem::remove_all(work_dir());
  return t;
}

}  // namespace

TEST(E2eStudy, Issue6AcceptanceTwentyRandomTubes) {
  const auto t =
      run_study(test::issue6_chain(), "issue 6 chain (exp_decay 1e5 1/s, port fit)", true);
  EXPECT_GE(t.cmcm, 19);
  EXPECT_GE(t.lm, 19);
}

TEST(E2eStudy, SeedChainOnTheSameTubes) {
  // The seed's drive and Prony features alone: recorded, and the issue 6 chain
  // must not do worse on any count.
  const auto seed =
      run_study(test::seed_chain(), "seed chain (exp_decay 3000 1/s, Prony features)", true);
  auto fast_prony = test::issue6_chain();
  fast_prony.port_fit = false;
  const auto prony = run_study(fast_prony, "exp_decay 1e5 1/s, Prony features", false);
  auto seed_fit = test::seed_chain();
  seed_fit.port_fit = true;
  const auto fit = run_study(seed_fit, "exp_decay 3000 1/s, port fit", false);
  const auto best = run_study(test::issue6_chain(), "issue 6 chain", false);
  for (const auto& other : {seed, prony, fit}) {
    EXPECT_GE(best.cmcm, other.cmcm);
    EXPECT_GE(best.lm, other.lm);
  }
  // The seed's drive with 4× the shots and the port fit: the lever that does not
  // depend on the noise being relative to the record's std (docs/update-methods.md).
  auto seed64 = test::seed_chain();
  seed64.plan.shots = 64;
  seed64.port_fit = true;
  const auto avg = run_study(seed64, "exp_decay 3000 1/s, 64 shots, port fit", true);
  EXPECT_GE(avg.cmcm, 19);
  EXPECT_GE(avg.lm, 19);
}
