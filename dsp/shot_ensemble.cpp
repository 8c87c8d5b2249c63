#include "dsp/shot_ensemble.hpp"

#include <cmath>
#include <complex>
#include <optional>
#include <stdexcept>
#include <string>

#include "dsp/fft.hpp"
#include "dsp/record_tail.hpp"

namespace piezo::dsp {

using cd = std::complex<double>;

ShotEnsemble impedance_shot_ensemble(const std::vector<DividerRecord>& shots, const ShotEnsembleOptions& opt) {
  const int n = static_cast<int>(shots.size());
  if (n < 3)
    throw std::invalid_argument("impedance_shot_ensemble: needs at least 3 repeated shots for a jackknife (got " +
                                std::to_string(n) + ")");
  if (!(opt.fmax_hz > opt.fmin_hz && opt.fmin_hz >= 0))
    throw std::invalid_argument("impedance_shot_ensemble: need 0 <= fmin < fmax");
  std::vector<Eigen::VectorXcd> x2(n), xi(n);
  double fs = 0, r1 = 0;
  Eigen::Index len = 0;
  std::vector<DividerSignals> sigs;
  for (int s = 0; s < n; ++s) sigs.push_back(prepare_divider(shots[s], "impedance_shot_ensemble", opt.prep));
  // The record's end (dsp/record_tail.hpp): the drive's late-time decay from
  // the shot-averaged v1, each shot's end levels fitted with it.
  RecordTail tail;
  if (opt.tail_correction && sigs.front().size() > 0) {
    Eigen::VectorXd mean_v1 = Eigen::VectorXd::Zero(sigs.front().size());
    bool same = true;
    for (const auto& sg : sigs) {
      if (sg.size() != mean_v1.size()) same = false;
      else mean_v1 += sg.v1;
    }
    if (same) tail = measure_tail(mean_v1 / double(n));
  }
  for (int s = 0; s < n; ++s) {
    DividerSignals& sig = sigs[static_cast<std::size_t>(s)];
    if (s == 0) {
      fs = sig.sample_rate_hz;
      r1 = sig.r1_ohm;
      len = sig.size();
    } else if (sig.size() != len || sig.sample_rate_hz != fs || sig.r1_ohm != r1) {
      throw std::invalid_argument("impedance_shot_ensemble: shot " + std::to_string(s) +
                                  " differs from shot 0 in length, sample rate or R1");
    }
    std::optional<TailCorrection> t2, ti;
    if (opt.tail_correction) t2.emplace(sig.v2, tail), ti.emplace(sig.i, tail);
    difference_in_place(sig);
    x2[s] = rfft(sig.v2, static_cast<std::size_t>(len));
    xi[s] = rfft(sig.i, static_cast<std::size_t>(len));
    if (opt.tail_correction)
      for (Eigen::Index k = 0; k < x2[s].size(); ++k) {
        x2[s][k] += t2->at_bin(k);
        xi[s][k] += ti->at_bin(k);
      }
    if (opt.linear_drive)  // i = (v1 − v2)/R1: the v1 part scaled by sinc²(f/fs)
      for (Eigen::Index k = 1; k < x2[s].size(); ++k) {
        const double x = M_PI * double(k) / double(len);
        const double sinc2 = std::pow(std::sin(x) / x, 2);
        xi[s][k] = sinc2 * xi[s][k] + (sinc2 - 1.0) * x2[s][k] / sig.r1_ohm;
      }
  }
  const double df = fs / double(len);
  // Bin groups: single bins, or log bands of the requested relative width.
  std::vector<std::pair<Eigen::Index, Eigen::Index>> groups;  // [first, last]
  for (Eigen::Index k = 1; k < x2[0].size(); ++k) {
    const double f = df * double(k);
    if (f < opt.fmin_hz || f > opt.fmax_hz) continue;
    if (!groups.empty() && opt.band_relative_width > 0 &&
        df * double(k - groups.back().first) < opt.band_relative_width * df * double(groups.back().first))
      groups.back().second = k;
    else
      groups.emplace_back(k, k);
  }
  if (groups.size() < 2) throw std::invalid_argument("impedance_shot_ensemble: fewer than 2 bins in [fmin, fmax]");
  ShotEnsemble out;
  const auto m = static_cast<Eigen::Index>(groups.size());
  out.f_hz.resize(m);
  out.z_ohm.resize(m);
  out.sigma_log_mag.resize(m);
  out.sigma_phase.resize(m);
  out.shots = n;
  out.samples = static_cast<std::size_t>(len);
  for (Eigen::Index q = 0; q < m; ++q) {
    const auto [a, b] = groups[static_cast<std::size_t>(q)];
    // Sums per shot over the band (a band is the coherent sum of its bins:
    // V2 and I summed alike, so Z is their ratio, weighted by |I|).
    std::vector<cd> s2(n), si(n);
    cd t2 = 0, ti = 0;
    double fw = 0, w = 0;
    for (int s = 0; s < n; ++s) {
      for (Eigen::Index k = a; k <= b; ++k) {
        s2[s] += x2[s][k];
        si[s] += xi[s][k];
      }
      t2 += s2[s];
      ti += si[s];
    }
    for (Eigen::Index k = a; k <= b; ++k) {
      double wk = 0;
      for (int s = 0; s < n; ++s) wk += std::norm(xi[s][k]);
      fw += wk * df * double(k);
      w += wk;
    }
    const cd z = t2 / ti;  // i = (v1 − v2)/R1 already
    std::vector<cd> lz(n);
    cd mean = 0;
    for (int s = 0; s < n; ++s) {
      lz[s] = std::log((t2 - s2[s]) / (ti - si[s]));
      // Unwrap the phase of each delete-one estimate around the full estimate's.
      const double d = std::remainder(lz[s].imag() - std::arg(z), 2 * M_PI);
      lz[s] = cd(lz[s].real(), std::arg(z) + d);
      mean += lz[s];
    }
    mean /= double(n);
    double vr = 0, vi = 0;
    for (int s = 0; s < n; ++s) {
      vr += std::pow(lz[s].real() - mean.real(), 2);
      vi += std::pow(lz[s].imag() - mean.imag(), 2);
    }
    const double jk = double(n - 1) / double(n);
    out.f_hz[q] = w > 0 ? fw / w : df * double(a);
    out.z_ohm[q] = z;
    out.sigma_log_mag[q] = jk * vr;  // variances for now
    out.sigma_phase[q] = jk * vi;
  }
  const Eigen::VectorXd vr = out.sigma_log_mag, vi = out.sigma_phase;
  const Eigen::Index k = std::max(0, opt.smooth_points);
  for (Eigen::Index q = 0; q < m; ++q) {
    const Eigen::Index a = std::max<Eigen::Index>(0, q - k), b = std::min<Eigen::Index>(m - 1, q + k);
    out.sigma_log_mag[q] = std::sqrt(vr.segment(a, b - a + 1).mean());
    out.sigma_phase[q] = std::sqrt(vi.segment(a, b - a + 1).mean());
  }
  return out;
}

}  // namespace piezo::dsp
