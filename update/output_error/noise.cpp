// The record's noise and the DAQ offsets' whitening (noise.hpp).
#include "update/output_error/noise.hpp"

#include <Eigen/SVD>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>

#include "dsp/prony_ss.hpp"

namespace piezo::update::oe {

namespace {
// The record's white-noise estimates (of its samples alone, not of θ) are
// kept beside its baseline columns (Problem::kept_column: kinds 0–2) under
// kind −1 and a fingerprint of the samples: problems that share columns may
// hold other records of the same shape (the columns do not depend on the
// samples; these estimates do).
Problem::ColumnKey white_noise_key(const Averaged& rec) {
  std::array<std::uint64_t, 4> lane{0x9E3779B97F4A7C15ull, 0xC2B2AE3D27D4EB4Full, 0x165667B19E3779F9ull,
                                    0x27D4EB2F165667C5ull};
  std::size_t k = 0;
  auto mix = [&](const std::vector<double>& v) {
    for (double x : v) {
      std::uint64_t b;
      std::memcpy(&b, &x, sizeof b);
      std::uint64_t& h = lane[k++ & 3];
      h = (h ^ b) * 0x100000001B3ull;
      h ^= h >> 29;
    }
    lane[0] ^= v.size();
  };
  mix(rec.v1);
  mix(rec.v2);
  for (const auto& d : rec.dev1) mix(d);
  for (const auto& d : rec.dev2) mix(d);
  const std::uint64_t h = (lane[0] * 31 + lane[1]) * 31 + lane[2] * 7 + lane[3];
  return {-1, static_cast<int>(rec.shots), static_cast<double>(h >> 11)};  // (53 bits: exact, never NaN)
}
}  // namespace

RecordNoise record_noise(Problem& prob, const Averaged& rec, const std::vector<cd>& t) {
  RecordNoise out;
  const std::size_t n = rec.v1.size();
  if (rec.shots >= 2) {
    double ss = 0;
    std::size_t m = 0;
    for (std::size_t k = 0; k < rec.dev1.size(); ++k) {
      const Eigen::VectorXd e = prob.deviation(t, rec.dev1[k], rec.dev2[k]);
      ss += e.squaredNorm();
      m += static_cast<std::size_t>(e.size());
    }
    out.source = "shots (" + std::to_string(rec.shots) + ")";
    out.dof = double(m) * double(rec.shots - 1) / double(rec.shots);
    // per-shot variance ss/((K−1)·M/K·…): Σ_k ‖e_k‖² = (K−1)/K·K·M·σ², the average's σ²/K
    const double var_shot = ss / (double(m) * double(rec.shots - 1) / double(rec.shots));
    double q1 = 0, q2 = 0;
    for (std::size_t k = 0; k < rec.dev1.size(); ++k)
      for (std::size_t i = 0; i < n; ++i) {
        q1 += rec.dev1[k][i] * rec.dev1[k][i];
        q2 += rec.dev2[k][i] * rec.dev2[k][i];
      }
    out.ch1 = std::sqrt(q1 / (double(n) * double(rec.shots - 1)) / double(rec.shots));
    out.ch2 = std::sqrt(q2 / (double(n) * double(rec.shots - 1)) / double(rec.shots));
    out.sigma = std::sqrt(var_shot / double(rec.shots));
    // Shots that differ by more than white noise (issue 40 item 3): each
    // shot's own offset, hum at its own phase, 1/f wander — slow
    // disturbances that average into one baseline of the averaged record,
    // which the fit models (baseline.hpp), but that make the shots' spread a
    // gross overestimate of the noise (σ × 2-5 on a bench with 5 mV of hum:
    // every constant then "not identifiable", the baseline never significant).
    // The white part of each shot's deviation from the mean, by the same
    // high-pass estimator as a single record's; used where the spread exceeds
    // it by half again in variance (white noise alone: the two agree within
    // a few percent at these sample counts).
    const auto k_shots = static_cast<double>(rec.shots);
    // (of the record alone: kept with its columns for the next call — the
    // fit's answer, the other predictions on one held-out record)
    const Eigen::VectorXd h = prob.kept_column(white_noise_key(rec), [&] {
      double h1 = 0, h2 = 0;
      for (std::size_t k = 0; k < rec.dev1.size(); ++k) {
        const Eigen::Map<const Eigen::VectorXd> a(rec.dev1[k].data(), static_cast<Eigen::Index>(n)),
            b(rec.dev2[k].data(), static_cast<Eigen::Index>(n));
        const double e1 = dsp::estimate_noise_std(a), e2 = dsp::estimate_noise_std(b);
        h1 += e1 * e1;
        h2 += e2 * e2;
      }
      return Eigen::Vector2d(h1, h2).eval();
    });
    const double h1 = h[0], h2 = h[1];
    // A deviation from the mean of K holds (K − 1)/K of a shot's variance.
    const double d = double(rec.dev1.size()) * (k_shots - 1.0) / k_shots;
    const double w1 = std::sqrt(h1 / d / k_shots), w2 = std::sqrt(h2 / d / k_shots);  // of the average
    const double sigma_white = prob.propagated_sigma(t, w1, w2);
    if (sigma_white > 0 && std::isfinite(sigma_white) && out.sigma * out.sigma > 1.5 * sigma_white * sigma_white) {
      out.source = "shots (" + std::to_string(rec.shots) + "), white part: the shots differ by slow disturbances (" +
                   std::to_string(out.sigma / sigma_white).substr(0, 4) + " times the white noise)";
      out.ch1 = w1;
      out.ch2 = w2;
      out.sigma = sigma_white;
      out.dof = 0.2 * double(n) * double(rec.dev1.size());
    }
    return out;
  }
  double s1 = 0, s2 = 0;
  if (rec.pretrigger >= 64 && rec.pretrigger < n) {
    for (std::size_t i = 0; i < rec.pretrigger; ++i) {
      s1 += rec.v1[i] * rec.v1[i];
      s2 += rec.v2[i] * rec.v2[i];
    }
    s1 = std::sqrt(s1 / double(rec.pretrigger - 1));
    s2 = std::sqrt(s2 / double(rec.pretrigger - 1));
    out.source = "pretrigger (" + std::to_string(rec.pretrigger) + " samples)";
    out.dof = double(rec.pretrigger - 1);
  } else {
    const Eigen::VectorXd e = prob.kept_column(white_noise_key(rec), [&] {
      const Eigen::Map<const Eigen::VectorXd> a(rec.v1.data(), static_cast<Eigen::Index>(n)),
          b(rec.v2.data(), static_cast<Eigen::Index>(n));
      return Eigen::Vector2d(dsp::estimate_noise_std(a), dsp::estimate_noise_std(b)).eval();
    });
    s1 = e[0];
    s2 = e[1];
    out.source = "high-pass estimate of each channel";
    // The median of |6th differences| of overlapping windows: about a fifth
    // of the samples' worth of independent information.
    out.dof = 0.2 * double(n);
  }
  out.ch1 = s1;
  out.ch2 = s2;
  out.sigma = prob.propagated_sigma(t, s1, s2);
  return out;
}

OffsetWhitening::OffsetWhitening(Problem& prob, const Averaged& rec,
                                 const std::vector<cd>& t_nominal, double sigma) {
  // u = L ∗ (T ∗ 0 − 1), the filtered error of a unit offset on v2: the
  // baseline's P0 column (L ∗ 1, T·0 − (−1) being 1 exactly), which the
  // problem keeps — and the predictions on one held-out record share.
  u = baseline_columns(prob, rec, t_nominal, 0, 0.0, 0).col(0);
  uu = u.squaredNorm();
  if (rec.pretrigger >= 16 && rec.pretrigger < rec.v1.size()) {
    double s1 = 0, s2 = 0;  // the (averaged) record's idle noise: its mean was removed
    for (std::size_t i = 0; i < rec.pretrigger; ++i) {
      s1 += rec.v1[i] * rec.v1[i];
      s2 += rec.v2[i] * rec.v2[i];
    }
    const double p = double(rec.pretrigger);
    const double tau2 = (s1 + s2) / (p - 1.0) / p;
    shrink = 1.0 - 1.0 / std::sqrt(1.0 + tau2 * uu / (sigma * sigma));
    dof = 0;
    model = "pretrigger mean removed, its error marginalised";
  } else {
    model = "unknown (no pretrigger): projected out";
  }
}

void OffsetWhitening::use(const DisturbanceModel& d, Problem& prob, const Averaged& rec,
                          const std::vector<cd>& t) {
  disturbances = d;
  if (!d.any()) return;
  pink = d.pink ? std::make_shared<const PinkFilter>(prob.samples(), d.pink_b) : nullptr;
  columns = d.baseline ? baseline_columns(prob, rec, t, d.poly_degree, d.mains_hz, d.harmonics)
                       : baseline_columns(prob, rec, t, 0, 0.0, 0);
  Eigen::MatrixXd cw(columns.rows(), columns.cols());
  for (Eigen::Index c = 0; c < columns.cols(); ++c) cw.col(c) = pink ? (*pink)(columns.col(c)) : columns.col(c);
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(cw, Eigen::ComputeThinU);
  int rank = 0;
  while (rank < svd.singularValues().size() && svd.singularValues()[rank] > 1e-9 * svd.singularValues()[0]) ++rank;
  q = svd.matrixU().leftCols(rank);
  dof = rank;
  std::string m;
  if (d.baseline) {
    m = "baseline projected out: offset and slope to degree " + std::to_string(d.poly_degree);
    if (d.harmonics > 0)
      m += ", mains hum " + std::to_string(static_cast<int>(d.mains_hz)) + " Hz with " +
           std::to_string(d.harmonics) + " harmonic(s)";
  } else {
    m = "offset projected out";
  }
  if (pink) m += "; 1/f noise whitened";
  model = m;
}

}  // namespace piezo::update::oe
