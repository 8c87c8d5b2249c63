// Issue 34's acceptance on the refsim controls (../shared/corpus/refsim-v1,
// another tool's captures, no effect injected): `figures CAP.h5` (--method oe,
// the default for a capture: the updated FE model's short- and open-circuit
// modes, σ from the constants' covariance) against two independent truths —
//   A  our FE at the truth's constants and β (truth.json; the same port-model
//      figures, no fit): what a perfect fit would give;
//   B  the truth's own impedance (truth_z.csv, the other tool's direct FE
//      solves on its own mesh).
// Against A (the bounds): the strongest mode's k_eff (IEEE 176)
// within 2 % and 3σ; every reported mode's fs and fp within 0.5 % and 3σ —
// counted and printed; asserted as expect_figure says.
// Against B: the frequency of the strongest mode's largest Re Z (what the raw
// curve shows of its parallel resonance) within 0.5 % + 3σ of fp.
// make test runs two controls (one shot, four shots); make validate all six.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "acquisition/capture_file.hpp"
#include "dsp/equivalent_circuit.hpp"
#include <complex>
#include "jobs/figures_job.hpp"
#include "jobs/pipeline/capture_fit.hpp"
#include "model/material.hpp"
#include "update/model_figures.hpp"

namespace {
namespace fs = std::filesystem;
using namespace piezo;
const fs::path kCorpus = fs::path(PIEZO_SOURCE_DIR) / ".." / "shared" / "corpus" / "refsim-v1";

#ifdef PIEZO_MODEL_FIGURES_ALL
const char* const kCases[] = {"03", "11", "12", "15", "18", "20"};
#else
const char* const kCases[] = {"12", "11"};
#endif

const dsp::CircuitModeFigures* strongest(const std::vector<dsp::CircuitModeFigures>& ms) {
  const dsp::CircuitModeFigures* best = nullptr;
  for (const auto& m : ms)
    if (std::isfinite(m.k_eff_ieee176.value) && (!best || m.k_eff_ieee176.value > best->k_eff_ieee176.value))
      best = &m;
  return best;
}

const dsp::CircuitModeFigures* nearest(const std::vector<dsp::CircuitModeFigures>& ms, double fs_hz) {
  const dsp::CircuitModeFigures* best = nullptr;
  for (const auto& m : ms)
    if (!best || std::abs(m.fs_hz.value - fs_hz) < std::abs(best->fs_hz.value - fs_hz)) best = &m;
  return best && std::abs(best->fs_hz.value / fs_hz - 1) < 0.02 ? best : nullptr;
}

struct TrueZ {
  std::vector<double> f;
  std::vector<std::complex<double>> z;
};
TrueZ read_truth_z(const fs::path& csv) {
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);  // f_hz,re_ohm,im_ohm
  TrueZ t;
  while (std::getline(in, line)) {
    double a, b, c;
    if (std::sscanf(line.c_str(), "%lf,%lf,%lf", &a, &b, &c) == 3) {
      t.f.push_back(a);
      t.z.push_back({b, c});
    }
  }
  return t;
}

// The frequency of the largest Re Z in [lo, hi] (the parallel resonance as a
// raw curve shows it; lossy, so a little off the lossless fp): on the truth's
// 100 Hz grid, refined by a parabola through the three points around it.
double max_resistance_hz(const TrueZ& t, double lo, double hi) {
  std::size_t best = 0;
  for (std::size_t i = 1; i + 1 < t.f.size(); ++i)
    if (t.f[i] >= lo && t.f[i] <= hi && (best == 0 || t.z[i].real() > t.z[best].real())) best = i;
  const double y0 = t.z[best - 1].real(), y1 = t.z[best].real(), y2 = t.z[best + 1].real();
  const double d = y0 - 2 * y1 + y2;
  return t.f[best] + (d != 0 ? 0.5 * (y0 - y2) / d : 0.0) * (t.f[best + 1] - t.f[best]);
}
double max_resistance_hz(const dsp::EquivalentCircuit& c, double lo, double hi) {
  double fb = lo, rb = -1;
  for (int i = 0; i <= 20000; ++i) {
    const double f = lo + (hi - lo) * i / 20000.0, r = c.impedance(f).real();
    if (r > rb) {
      rb = r;
      fb = f;
    }
  }
  return fb;
}

double rel(double a, double b) { return a / b - 1.0; }

// The bound (`bound`, relative) and 3σ. Asserted: the error within 3σ
// always (a sigma far smaller than the error is the worst defect), and within
// the bound whenever the figure's own relative σ is below a third of it (the
// capture supports that precision). A one-shot capture at 4 % noise gives
// k_eff a 3 % σ: its error may then exceed 2 % honestly — counted and printed
// against the 6/6, not asserted.
void expect_figure(const char* c, const char* what, double err, double z, double rel_sigma, double bound) {
  EXPECT_LT(std::abs(z), 3.0) << c << ": " << what << " off by " << 100 * err << " % = " << z << " sigma";
  if (rel_sigma < bound / 3) {
    EXPECT_LT(std::abs(err), bound) << c << ": " << what << " off by " << 100 * err << " % with a sigma of "
                                    << 100 * rel_sigma << " %";
  }
}

TEST(ModelFiguresCorpus, StrongestKeffAndEveryModesFsFpAgainstTheTruth) {
  if (!fs::exists(kCorpus / "12" / "fit.h5")) GTEST_SKIP() << "no corpus at " << kCorpus;
  int keff_ok = 0, modes = 0, modes_ok = 0;
  for (const char* c : kCases) {
    std::ifstream tj(kCorpus / c / "truth.json");
    const auto truth = nlohmann::json::parse(tj);
    ASSERT_TRUE(truth["effect"].is_null()) << c << " is not a control";
    jobs::FiguresRequest req;
    req.file = (kCorpus / c / "fit.h5").string();
    const auto r = jobs::run_figures(req);
    ASSERT_TRUE(r.model_figures) << c;
    const double band_hi = r.f_hz[r.f_hz.size() - 1];
    // A: our FE at the truth's constants.
    const auto cap = acq::read_capture(req.file);
    const auto m = jobs::capture_model(cap, "apc850", true);
    update::TubeParams tp;
    tp.y_e11 = truth["material"]["YE11_pa"];
    tp.nu12 = truth["material"]["nu12"];
    tp.d31 = truth["material"]["d31_c_per_n"];
    tp.eps_t33 = truth["material"]["epsT33_rel"].get<double>() * model::kEps0;
    update::OeLoss loss;
    loss.beta_s = truth["damping"]["rayleigh_beta_s"];
    const auto a = update::model_figures(*m.solver, m.cls, tp, loss, {}, 0, band_hi, update::OeOptions{}.modal);
    // B: the truth's own impedance.
    const auto tz = read_truth_z(kCorpus / c / "truth_z.csv");
    const auto* s = strongest(r.fit.modes);
    ASSERT_TRUE(s) << c;
    const auto* sa = nearest(a.modes, s->fs_hz.value);
    ASSERT_TRUE(sa) << c << ": the strongest mode at " << s->fs_hz.value << " Hz is not in the truth's model";
    const double ek = rel(s->k_eff_ieee176.value, sa->k_eff_ieee176.value);
    const double zk = (s->k_eff_ieee176.value - sa->k_eff_ieee176.value) / s->k_eff_ieee176.sigma;
    std::printf("case %s: strongest mode fs %.1f Hz: k_eff %.4f +/- %.4f, truth(A) %.4f: %+.2f %% (%+.2f sigma)", c,
                s->fs_hz.value, s->k_eff_ieee176.value, s->k_eff_ieee176.sigma, sa->k_eff_ieee176.value, 100 * ek,
                zk);
    // The strongest mode's largest resistance, model against truth (B): the
    // model's σ of fp stands for it (the same mode's parallel resonance).
    const double lo = s->fs_hz.value, hi = 1.2 * s->fp_hz.value;
    const double rm = max_resistance_hz(r.fit.circuit, lo, hi), rt = max_resistance_hz(tz, lo, hi);
    std::printf("; max Re Z %.1f Hz, truth_z(B) %.1f Hz: %+.3f %% (%+.2f sigma)", rm, rt, 100 * rel(rm, rt),
                (rm - rt) / s->fp_hz.sigma);
    EXPECT_LT(std::abs(rm - rt), 0.005 * rt + 3 * s->fp_hz.sigma) << c << ": against truth_z";
    std::printf("\n");
    keff_ok += std::abs(ek) < 0.02 && std::abs(zk) < 3;
    expect_figure(c, "strongest k_eff", ek, zk, s->k_eff_ieee176.sigma / s->k_eff_ieee176.value, 0.02);
    for (const auto& mm : r.fit.modes) {
      const auto* ma = nearest(a.modes, mm.fs_hz.value);
      ++modes;
      if (!ma) {
        ADD_FAILURE() << c << ": mode at " << mm.fs_hz.value << " Hz not in the truth's model";
        continue;
      }
      const double es = rel(mm.fs_hz.value, ma->fs_hz.value), ep = rel(mm.fp_hz.value, ma->fp_hz.value);
      const double zs = (mm.fs_hz.value - ma->fs_hz.value) / mm.fs_hz.sigma;
      const double zp = (mm.fp_hz.value - ma->fp_hz.value) / mm.fp_hz.sigma;
      std::printf("  mode fs %.1f +/- %.1f (A %.1f, %+.3f %%, %+.2f sigma)  fp %.1f +/- %.1f (A %.1f, %+.3f %%, %+.2f sigma)\n",
                  mm.fs_hz.value, mm.fs_hz.sigma, ma->fs_hz.value, 100 * es, zs, mm.fp_hz.value, mm.fp_hz.sigma,
                  ma->fp_hz.value, 100 * ep, zp);
      // A weak mode inside a strong one's fs-fp interval has no fp (model and truth alike).
      const bool no_fp = !std::isfinite(mm.fp_hz.value) && !std::isfinite(ma->fp_hz.value);
      modes_ok += std::abs(es) < 0.005 && std::abs(zs) < 3 && (no_fp || (std::abs(ep) < 0.005 && std::abs(zp) < 3));
      expect_figure(c, "fs", es, zs, mm.fs_hz.sigma / mm.fs_hz.value, 0.005);
      if (!no_fp) expect_figure(c, "fp", ep, zp, mm.fp_hz.sigma / mm.fp_hz.value, 0.005);
    }
  }
  std::printf("strongest k_eff within 2 %% and 3 sigma: %d/%zu; modes with fs and fp within 0.5 %% and 3 sigma: %d/%d\n",
              keff_ok, std::size(kCases), modes_ok, modes);
}

}  // namespace
