// Issue 19's acceptance on the refsim corpus (../shared/corpus/refsim-v1,
// another tool's captures): on each control case (no effect injected), the
// per-mode figures the pipeline reports ("Measure and update", replay: since
// issue 34 the output-error fit's updated model's modes, C^T still measured on
// the estimate) and those of the updated model's impedance curve against the
// per-mode BVD figures computed from the case's true impedance (truth_z.csv,
// written by that tool beside the capture). Asserted: C^T within 0.5 % (the
// issue's bound). Issue 34's own acceptance (against the FE's open- and
// short-circuit modes at the truth's constants): test_model_figures_corpus.cpp. fs, fp and k_eff of the strongest mode are printed, not
// asserted: from one 1-4 % noise shot the estimate's low-Q resonances (Qm ~30)
// move fs by 0.3-1 % and k_eff by 1-20 %, and the updated model's k_eff
// carries d31's 1-2 % sigma — the 0.5 % is met by the updated model on
// 4 of the 6 controls only (README, issue 19's note). make test runs two
// controls (a one-shot and a four-shot capture); make validate all six.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "dsp/mode_figures.hpp"
#include "jobs/pipeline/pipeline.hpp"

namespace {
namespace fs = std::filesystem;
using namespace piezo;
const fs::path kCorpus = fs::path(PIEZO_SOURCE_DIR) / ".." / "shared" / "corpus" / "refsim-v1";

struct TrueZ {
  Eigen::VectorXd f;
  Eigen::VectorXcd z;
};

TrueZ read_truth_z(const fs::path& file) {
  std::ifstream in(file);
  std::string line;
  std::getline(in, line);  // f_hz,re_ohm,im_ohm
  std::vector<double> f, re, im;
  while (std::getline(in, line)) {
    double a, b, c;
    if (std::sscanf(line.c_str(), "%lf,%lf,%lf", &a, &b, &c) == 3) {
      f.push_back(a);
      re.push_back(b);
      im.push_back(c);
    }
  }
  TrueZ t;
  t.f.resize(static_cast<Eigen::Index>(f.size()));
  t.z.resize(static_cast<Eigen::Index>(f.size()));
  for (std::size_t i = 0; i < f.size(); ++i) {
    t.f[static_cast<Eigen::Index>(i)] = f[i];
    t.z[static_cast<Eigen::Index>(i)] = {re[i], im[i]};
  }
  return t;
}

const dsp::ModeFigures* strongest(const dsp::ModeFiguresResult& r) {
  const dsp::ModeFigures* best = nullptr;
  for (const auto& m : r.modes)
    if (std::isfinite(m.k_eff.value) && (!best || m.k_eff.value > best->k_eff.value)) best = &m;
  return best;
}

double rel(double a, double b) { return a / b - 1.0; }

#ifdef PIEZO_MODE_FIGURES_ALL
const char* const kCases[] = {"11", "12", "15", "18", "20", "03"};
#else
const char* const kCases[] = {"12", "11"};
#endif

TEST(ModeFiguresCorpus, FreeCapacitanceWithinHalfAPercentOfTheTrueImpedance) {
  if (!fs::exists(kCorpus / "12" / "fit.h5")) GTEST_SKIP() << "no corpus at " << kCorpus;
  int checked = 0;
  for (const char* c : kCases) {
    std::ifstream tj(kCorpus / c / "truth.json");
    const auto truth = nlohmann::json::parse(tj);
    ASSERT_TRUE(truth["effect"].is_null()) << c << " is not a control";
    jobs::PipelineRequest req;
    req.replay_capture = (kCorpus / c / "fit.h5").string();
    req.replay_contained = false;
    req.diagnose = false;
    std::atomic<bool> cancel{false};
    const auto r = jobs::run_pipeline(req, {}, cancel);
    ASSERT_TRUE(r.mode_figures) << c;
    ASSERT_TRUE(r.mode_figures->error.empty()) << c << ": " << r.mode_figures->error;
    const auto& est = r.mode_figures->figures;
    const auto tz = read_truth_z(kCorpus / c / "truth_z.csv");
    dsp::ModeFigureOptions o;
    o.reference_hz = est.reference_used_hz;  // C^T where the estimate has it
    const auto tru = dsp::mode_figures(tz.f, tz.z, {}, o);
    const auto* me = strongest(est);
    const auto* mt = strongest(tru);
    const double e_fs = rel(me->fs_hz.value, mt->fs_hz.value), e_fp = rel(me->fp_hz.value, mt->fp_hz.value);
    const double e_k = rel(me->k_eff.value, mt->k_eff.value);
    const double e_ct = rel(est.free_capacitance_f.value, tru.free_capacitance_f.value);
    std::printf("case %s (%d shot(s)): fs %.2f / %.2f Hz (%+.3f %%), fp %.2f / %.2f Hz (%+.3f %%), k_eff %.4f / %.4f "
                "(%+.3f %%), C^T %.5g / %.5g F at %.0f Hz (%+.3f %%)\n",
                c, r.shots, me->fs_hz.value, mt->fs_hz.value, 100 * e_fs, me->fp_hz.value, mt->fp_hz.value, 100 * e_fp,
                me->k_eff.value, mt->k_eff.value, 100 * e_k, est.free_capacitance_f.value, tru.free_capacitance_f.value,
                est.reference_used_hz, 100 * e_ct);
    // … and those of the updated model's impedance (the pipeline's curve).
    for (const auto& cv : r.curves) {
      if (cv.label != "updated model") continue;
      Eigen::VectorXd f(static_cast<Eigen::Index>(cv.f_hz.size()));
      Eigen::VectorXcd z(f.size());
      for (Eigen::Index i = 0; i < f.size(); ++i) {
        f[i] = cv.f_hz[static_cast<std::size_t>(i)];
        z[i] = cv.z_ohm[static_cast<std::size_t>(i)];
      }
      const auto um = dsp::mode_figures(f, z, {}, o);
      if (const auto* mu = strongest(um))
        std::printf("  updated model: fs %+.3f %%, fp %+.3f %%, k_eff %+.3f %%, C^T %+.3f %% (grid %.0f..%.0f Hz, %zu points)\n",
                    100 * rel(mu->fs_hz.value, mt->fs_hz.value), 100 * rel(mu->fp_hz.value, mt->fp_hz.value),
                    100 * rel(mu->k_eff.value, mt->k_eff.value),
                    100 * rel(um.free_capacitance_f.value, tru.free_capacitance_f.value), cv.f_hz.front(), cv.f_hz.back(), cv.f_hz.size());
    }
    ASSERT_TRUE(me && mt) << c;
    EXPECT_LT(std::abs(e_ct), 0.005) << c;
    ++checked;
  }
  EXPECT_EQ(checked, static_cast<int>(std::size(kCases)));
}

}  // namespace
