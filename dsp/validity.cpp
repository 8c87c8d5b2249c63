#include "dsp/validity.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "dsp/divider.hpp"
#include "dsp/fft.hpp"
#include "dsp/prony_ss.hpp"
#include "dsp/signal_stats.hpp"

namespace piezo::dsp {

namespace {
using cd = std::complex<double>;

bool is_clipped(const DividerRecord& r) {
  ClipDetection c1, c2;
  c1.range_v = r.range_v(1);
  c2.range_v = r.range_v(2);
  return compute_stats(r.v1, c1).clipped || compute_stats(r.v2, c2).clipped;
}
}  // namespace

ValidityReport check_shots(std::span<const DividerRecord> records,
                           const PronyImpedanceOptions& prony, const ShotValidityOptions& opt) {
  if (records.empty()) throw std::invalid_argument("check_shots: no shot");
  ValidityReport rep;
  rep.shots.resize(records.size());
  // Spectra of the differenced records from t = 0 (the drive's step becomes an impulse).
  DividerPrep prep;
  prep.refuse_clipped = false;
  std::vector<Eigen::VectorXcd> x1, x2;
  std::size_t n = 0;
  for (const auto& r : records) {
    const std::size_t avail =
        r.v1.size() > r.pretrigger_samples ? r.v1.size() - r.pretrigger_samples : 0;
    n = n == 0 ? avail : std::min(n, avail);
  }
  prep.max_samples = n;
  double fs = records.front().sample_rate_hz;
  for (std::size_t k = 0; k < records.size(); ++k) {
    auto& sv = rep.shots[k];
    sv.clipped = is_clipped(records[k]);
    if (sv.clipped) sv.flags.emplace_back("clipped");
    DividerSignals s = prepare_divider(records[k], "check_shots", prep);
    difference_in_place(s);
    x1.push_back(rfft(s.v1, s.v1.size()));
    x2.push_back(rfft(s.v2, s.v2.size()));
  }
  const double fmax = opt.fmax_hz > 0 ? opt.fmax_hz : fs / 4;
  const double df = fs / double(n);
  std::vector<Eigen::Index> bins;
  for (Eigen::Index b = 1; b < x1.front().size(); ++b)
    if (df * double(b) >= opt.fmin_hz && df * double(b) <= fmax) bins.push_back(b);
  if (records.size() >= 2 && bins.size() >= 2) {
    const auto nb = static_cast<Eigen::Index>(bins.size());
    rep.f_hz.resize(nb);
    rep.coherence.resize(nb);
    Eigen::VectorXcd h(nb);
    std::size_t low = 0;
    for (Eigen::Index q = 0; q < nb; ++q) {
      const Eigen::Index b = bins[static_cast<std::size_t>(q)];
      cd g12 = 0;
      double g11 = 0, g22 = 0;
      for (std::size_t k = 0; k < records.size(); ++k) {
        g12 += std::conj(x1[k][b]) * x2[k][b];
        g11 += std::norm(x1[k][b]);
        g22 += std::norm(x2[k][b]);
      }
      rep.f_hz[q] = df * double(b);
      rep.coherence[q] = g11 > 0 && g22 > 0 ? std::norm(g12) / (g11 * g22) : 0.0;
      // The ensemble transfer for the per-shot check: the median of the shots'
      // own transfers (re, im), so that a stray shot does not pull it.
      std::vector<double> re, im;
      for (std::size_t k = 0; k < records.size(); ++k) {
        const cd t = std::abs(x1[k][b]) > 0 ? x2[k][b] / x1[k][b] : cd(0);
        re.push_back(t.real());
        im.push_back(t.imag());
      }
      auto median = [](std::vector<double>& v) {
        std::sort(v.begin(), v.end());
        const std::size_t m = v.size() / 2;
        return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
      };
      h[q] = cd(median(re), median(im));
      if (rep.coherence[q] < opt.min_coherence) ++low;
    }
    rep.low_coherence_fraction = double(low) / double(nb);
    for (std::size_t k = 0; k < records.size(); ++k) {
      cd num = 0;
      double a = 0, b2 = 0;
      for (Eigen::Index q = 0; q < nb; ++q) {
        const Eigen::Index b = bins[static_cast<std::size_t>(q)];
        const cd pred = h[q] * x1[k][b];
        num += std::conj(x2[k][b]) * pred;
        a += std::norm(x2[k][b]);
        b2 += std::norm(pred);
      }
      auto& sv = rep.shots[k];
      sv.coherence = a > 0 && b2 > 0 ? std::norm(num) / (a * b2) : 0.0;
      if (sv.coherence < opt.min_shot_coherence) sv.flags.emplace_back("low coherence");
    }
  }
  // Prony reconstruction of each shot at the estimate's order.
  PronyImpedanceOptions po = prony;
  if (opt.prony_samples) po.prep.max_samples = opt.prony_samples;
  po.prep.refuse_clipped = false;
  for (std::size_t k = 0; k < records.size(); ++k) {
    auto& sv = rep.shots[k];
    try {
      const auto m = fit_prony_impedance(records[k], po);
      const DividerSignals s = prepare_divider(records[k], "check_shots", po.prep);
      const double n1 = estimate_noise_std(s.v1), n2 = estimate_noise_std(s.v2);
      auto ratio = [](double res, double noise) {
        return noise > 0 ? res / noise : (res > 0 ? INFINITY : 1.0);
      };
      sv.reconstruction_ratio =
          std::max(ratio(m.fit.residual_rms[0], n1), ratio(m.fit.residual_rms[1], n2));
    } catch (const std::invalid_argument&) {
      sv.reconstruction_ratio = kNaN;
      sv.flags.emplace_back("Prony fit failed");
      continue;
    }
    if (!(sv.reconstruction_ratio <= opt.max_reconstruction_ratio))
      sv.flags.emplace_back("poor Prony reconstruction");
  }
  return rep;
}

}  // namespace piezo::dsp
