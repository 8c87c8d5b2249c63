// The slow disturbances' nuisance model of the output-error fit (baseline.hpp).
#include "update/output_error/baseline.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "dsp/fft.hpp"
#include "update/residual_regions.hpp"

namespace piezo::update::oe {

namespace {

constexpr double kLn1e3 = -6.907755278982137;  // ln 1e-3
constexpr double kPinkLr = 10.83;               // χ²₁ at p = 1e-3
constexpr double kBaselineShare = 0.02;         // baseline Δχ² over the transfer errors' χ², at least

// One FFT per size and thread (FFTW's plans execute on their own buffers).
dsp::RealFft& thread_fft(std::size_t n) {
  thread_local std::map<std::size_t, std::unique_ptr<dsp::RealFft>> ffts;
  auto& f = ffts[n];
  if (!f) f = std::make_unique<dsp::RealFft>(n);
  return *f;
}

// The orthogonal projection onto the columns' span (its rank: the singular
// values above 1e-9 of the largest) without forming a basis of it: a
// Householder QR of the columns and the SVD of the small R give the span's
// orthonormal basis as Q·U_R, and the disturbance test needs only ‖Pz‖² and
// z − Pz, a pass or two of the reflectors over z. (A JacobiSVD's thin U of
// the m × n columns — its own QR, then an m × n product — cost three times
// the work: 2-3 % of a replay.)
class SpanProjector {
 public:
  explicit SpanProjector(const Eigen::MatrixXd& c) : qr_(c), n_(std::min(c.rows(), c.cols())) {
    if (n_ == 0) return;
    const Eigen::MatrixXd r = qr_.matrixQR().topLeftCorner(n_, c.cols()).triangularView<Eigen::Upper>();
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(r, Eigen::ComputeFullU);
    const Eigen::VectorXd& sv = svd.singularValues();
    while (rank_ < sv.size() && sv[rank_] > 1e-9 * sv[0]) ++rank_;
    u_ = svd.matrixU().leftCols(rank_);
  }
  Eigen::Index rank() const { return rank_; }
  // ‖Pz‖²: the squared coordinates of z along the span's orthonormal basis.
  double norm2(const Eigen::VectorXd& z) const { return rank_ == 0 ? 0.0 : coordinates(z).squaredNorm(); }
  // z − Pz.
  Eigen::VectorXd residual(const Eigen::VectorXd& z) const {
    if (rank_ == 0) return z;
    Eigen::VectorXd w = Eigen::VectorXd::Zero(z.size());
    w.head(n_) = u_ * coordinates(z);
    return z - qr_.householderQ() * w;
  }

 private:
  Eigen::VectorXd coordinates(const Eigen::VectorXd& z) const {
    const Eigen::VectorXd y = qr_.householderQ().transpose() * z;
    return u_.transpose() * y.head(n_);
  }
  Eigen::HouseholderQR<Eigen::MatrixXd> qr_;
  Eigen::Index n_ = 0, rank_ = 0;
  Eigen::MatrixXd u_;  // R's leading left singular vectors (n × rank)
};

double legendre(int k, double x) {
  switch (k) {
    case 0: return 1.0;
    case 1: return x;
    case 2: return 0.5 * (3 * x * x - 1);
    default: return 0.5 * (5 * x * x * x - 3 * x);
  }
}

}  // namespace

PinkFilter::PinkFilter(std::size_t m, double b) : m_(m), n_(dsp::good_fft_size(2 * m)), b_(b) {
  w_.resize(n_ / 2 + 1);
  // Bin k of the N-point transform is k·M/N bins of the record's M-point one.
  for (std::size_t k = 0; k < w_.size(); ++k) {
    const double f_rel = k == 0 ? 0.5 : double(k) * double(m_) / double(n_);
    w_[k] = 1.0 / std::sqrt(1.0 + b_ / f_rel);
  }
}

Eigen::VectorXd PinkFilter::operator()(const Eigen::VectorXd& r) const {
  dsp::RealFft& fft = thread_fft(n_);
  std::vector<cd> x(fft.bins());
  fft.forward(r.data(), static_cast<std::size_t>(r.size()), x.data());
  for (std::size_t k = 0; k < x.size(); ++k) x[k] *= w_[k] / double(n_);
  Eigen::VectorXd out(r.size());
  fft.inverse(x.data(), out.data(), static_cast<std::size_t>(r.size()));
  return out;
}

int hum_harmonics(double mains_hz, double seconds) {
  int n = 0;
  for (int h = 1; h <= 3; ++h) n += h * mains_hz * seconds >= 0.5;
  return n;
}

Eigen::MatrixXd baseline_columns(Problem& prob, const Averaged& rec, const std::vector<cd>& t, int degree,
                                 double mains_hz, int harmonics) {
  const std::size_t n = rec.v1.size();
  const double fs = prob.sample_rate_hz();
  const double seconds = double(n) / fs;
  // Each column by its basis function: (0, k, 0) Legendre P_k, (1, h, f) and
  // (2, h, f) the cosine and sine of harmonic h of the mains f.
  std::vector<Problem::ColumnKey> keys;
  for (int k = 0; k <= degree; ++k) keys.emplace_back(0, k, 0.0);
  if (mains_hz > 0 && harmonics > 0)
    for (int h = 1; h <= 3; ++h) {
      if (!(h * mains_hz * seconds >= 0.5)) continue;
      keys.emplace_back(1, h, mains_hz);
      keys.emplace_back(2, h, mains_hz);
    }
  Eigen::MatrixXd cols(static_cast<Eigen::Index>(prob.samples()), static_cast<Eigen::Index>(keys.size()));
  // L ∗ (T ∗ 0 − (−b)) = L ∗ b: the residual of a baseline b on v1 (T ≈ 1 at
  // its frequencies), the negative of one on v2. T·0 − (−b) is b exactly:
  // the columns do not depend on t, and the problem keeps each (the
  // disturbance test, its mains frequencies and the whitening ask for the
  // same ones again).
  // A harmonic's cosine column is asked for just before its sine: one
  // sincos per sample makes both functions' values (glibc's sincos runs the
  // same code as its sin and cos: the same bits), the sine's kept for its
  // column here.
  std::optional<std::pair<Problem::ColumnKey, std::vector<double>>> sine_made;
  for (std::size_t c = 0; c < keys.size(); ++c) {
    const auto [kind, order, hz] = keys[c];
    cols.col(static_cast<Eigen::Index>(c)) = prob.kept_column(keys[c], [&, kind = kind, order = order, hz = hz] {
      std::vector<double> neg(n);
      if (kind == 2 && sine_made && sine_made->first == keys[c]) {
        neg = std::move(sine_made->second);
        sine_made.reset();
      } else if (kind == 1) {
        std::vector<double> neg_sin(n);
        for (std::size_t i = 0; i < n; ++i) {
          const double ph = kTwoPi * order * hz * double(i) / fs;
          double sn, cs;
          ::sincos(ph, &sn, &cs);
          neg[i] = -cs;
          neg_sin[i] = -sn;
        }
        sine_made.emplace(Problem::ColumnKey{2, order, hz}, std::move(neg_sin));
      } else {
        for (std::size_t i = 0; i < n; ++i) {
          if (kind == 0) {
            neg[i] = -legendre(order, n > 1 ? 2.0 * double(i) / double(n - 1) - 1.0 : 0.0);
          } else {
            const double ph = kTwoPi * order * hz * double(i) / fs;
            neg[i] = -std::sin(ph);
          }
        }
      }
      return Eigen::VectorXd(prob.deviation(t, std::vector<double>(n, 0.0), neg));
    });
  }
  return cols;
}

Eigen::MatrixXd transfer_error_columns(Problem& prob, const std::vector<cd>& t) {
  const std::vector<cd> zero(t.size(), cd(0.0, 0.0));
  const Eigen::VectorXd base = prob.residual_of(zero);  // −L ∗ v2
  // τ: a quarter of the band's period scale (the columns' sizes comparable).
  const double fmax = double(t.size() - 1) * prob.transfer_bin_hz();
  const double tau = fmax > 0 ? 1.0 / (kTwoPi * fmax / 2.5) : 0.0;
  // T^p·(jωτ)^q for p = 1..3, q = 0..2: the transfer errors of the bench's
  // effects to second order (T² is 1/(1 + R1·Y)² — a load on the tube; T³ its
  // square; the jω powers a delay, a capacitance, a loss angle's slope).
  // And T^p·ωτ (real): a loss angle's conductance ωC·tanδ, which no power
  // of jω makes (dielectric loss; refsim case 13's tanδ 0.019 read as a
  // baseline without it).
  Eigen::MatrixXd out(base.size(), 12);
  int c = 0;
  std::vector<cd> tp(t.begin(), t.end()), g(t.size());  // T^pw, by products (std::pow's exp/log cost more)
  for (int pw = 1; pw <= 3; ++pw) {
    if (pw > 1)
      for (std::size_t k = 0; k < t.size(); ++k) tp[k] *= t[k];
    for (int q = 0; q <= 3; ++q, ++c) {
      for (std::size_t k = 0; k < t.size(); ++k) {
        const double wt = kTwoPi * double(k) * prob.transfer_bin_hz() * tau;
        const cd f = q == 0 ? cd(1.0, 0.0) : q == 1 ? cd(0.0, wt) : q == 2 ? cd(-wt * wt, 0.0) : cd(wt, 0.0);
        g[k] = tp[k] * f;
      }
      out.col(c) = prob.residual_of(g) - base;
    }
  }
  return out;
}

DisturbanceModel decide_disturbances(Problem& prob, const Averaged& rec, const std::vector<cd>& t,
                                     const Eigen::VectorXd& r, double sigma, double ch1, double ch2,
                                     double sample_rate_hz, double mains_hz) {
  DisturbanceModel d;
  const Eigen::Index m = r.size();
  if (m < 32 || !(sigma > 0)) return d;
  const Eigen::VectorXd z = r / sigma;
  const double seconds = double(rec.v1.size()) / sample_rate_hz;

  // What a bench effect leaves at the optimum is a transfer error δT·v1 —
  // smooth and slow for the exp_decay drive's v1 (a gain error is g·v2), so
  // a polynomial and a 1/f weighting would take it. A baseline does not
  // follow v1: it is measured beyond the generic transfer errors
  // L ∗ (δT_k·v1), δT_k ∈ {T, T(1 − T), jωτ·T, jωτ·T(1 − T)} (gain, loading
  // and series impedance, skew, parallel capacitance and dielectric loss to
  // first order; τ = 1/(2π·band); to second order in transfer_error_columns),
  // which are projected out of both sides of
  // the test, and the 1/f noise is estimated from the residual without them.
  const Eigen::MatrixXd errs = transfer_error_columns(prob, t);
  auto with_errors = [&](const Eigen::MatrixXd& c) {
    Eigen::MatrixXd a(c.rows(), c.cols() + errs.cols());
    a << c, errs;
    return a;
  };
  // The baseline: the columns' Δχ² beyond the offset's, per mains frequency tried.
  const auto q_off = std::make_shared<const SpanProjector>(with_errors(baseline_columns(prob, rec, t, 0, 0, 0)));
  const double chi_off = q_off->norm2(z);
  d.transfer_error_chi2 = SpanProjector(errs).norm2(z);
  std::vector<double> tried = mains_hz > 0 ? std::vector<double>{mains_hz} : std::vector<double>{50.0, 60.0};
  d.mains_known = mains_hz > 0;
  double best_logp = 0, best_delta = 0;
  std::vector<double> deltas;
  std::shared_ptr<const SpanProjector> q_best = q_off;
  for (double f : tried) {
    const int h = hum_harmonics(f, seconds);
    const auto q =
        std::make_shared<const SpanProjector>(with_errors(baseline_columns(prob, rec, t, d.poly_degree, f, h)));
    const double delta = std::max(0.0, q->norm2(z) - chi_off);
    const int dof = static_cast<int>(q->rank()) - static_cast<int>(q_off->rank());
    deltas.push_back(delta);
    const double logp = dof > 0 ? log_gamma_tail((dof + 1) / 2, 0.5 * delta) + std::log(double(tried.size())) : 0.0;
    if (deltas.size() == 1 || delta > best_delta) {
      best_delta = delta;
      best_logp = std::min(0.0, logp);
      d.mains_hz = f;
      d.harmonics = h;
      d.baseline_dof = dof;
      q_best = q;
    }
  }
  d.baseline_delta_chi2 = best_delta;
  d.baseline_log10_p = best_logp / std::log(10.0);
  // … and only when it is not dwarfed by the residual along the transfer
  // errors: a bench effect's misfit beyond second order also leaves a slow
  // part (refsim cases 13 and 14, dielectric loss: baseline Δχ² 0.3-0.4 % of
  // the transfer errors' χ²), a baseline's Δχ² was 8-99 % of it on our
  // disturbed study's captures. The cut between the two, 2 %, is a measured
  // heuristic (docs/update-methods.md), not a test of chance.
  d.baseline = best_logp < kLn1e3 && best_delta > kBaselineShare * d.transfer_error_chi2;
  d.mains_distinguishable =
      d.mains_known || (deltas.size() == 2 && d.harmonics > 0 && std::abs(deltas[0] - deltas[1]) > kPinkLr);

  // 1/f noise: the periodogram of the residual without its baseline (or offset).
  const SpanProjector& q = d.baseline ? *q_best : *q_off;
  const Eigen::VectorXd zp = q.residual(z);
  dsp::RealFft& fft = thread_fft(static_cast<std::size_t>(m));
  std::vector<cd> x(fft.bins());
  fft.forward(zp.data(), static_cast<std::size_t>(m), x.data());
  const Eigen::VectorXd shape = prob.residual_psd(t, ch1, ch2);
  const auto half = static_cast<std::size_t>(m / 2);
  double total = 0;  // two-sided sum of the shape
  for (std::size_t j = 0; j <= half && j < static_cast<std::size_t>(shape.size()); ++j)
    total += (j == 0 || 2 * j == static_cast<std::size_t>(m)) ? shape[Eigen::Index(j)] : 2 * shape[Eigen::Index(j)];
  if (!(total > 0)) return d;
  const double top = shape.maxCoeff();
  // The projection removes about one bin per two columns at the bottom.
  const std::size_t j0 = 1 + (static_cast<std::size_t>(q.rank() - errs.cols()) + 1) / 2;
  std::vector<double> zeta, g;
  std::vector<int> octave;
  for (std::size_t j = j0; j < half && j < static_cast<std::size_t>(shape.size()); ++j) {
    const double s = shape[Eigen::Index(j)];
    if (!(s > 1e-4 * top)) continue;
    const double expect = double(m) * double(m) * s / total;
    zeta.push_back(std::norm(x[j]) / expect);
    g.push_back(1.0 / double(j));
    octave.push_back(static_cast<int>(std::floor(std::log2(double(j)))));
  }
  if (zeta.size() < 16) return d;
  // Octave medians (robust to a misfit near a few modes) → b by weighted LS.
  std::map<int, std::vector<std::size_t>> groups;
  for (std::size_t i = 0; i < zeta.size(); ++i) groups[octave[i]].push_back(i);
  struct Oct {
    double e, g, n;
  };
  std::vector<Oct> octs;
  for (auto& [o, idx] : groups) {
    std::vector<double> v;
    double gs = 0;
    for (auto i : idx) v.push_back(zeta[i]), gs += g[i];
    double e;
    if (v.size() >= 3) {
      std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
      e = v[v.size() / 2] / std::log(2.0);
    } else {
      e = 0;
      for (double a : v) e += a;
      e /= double(v.size());
    }
    octs.push_back({e, gs / double(idx.size()), double(idx.size())});
  }
  double b = 0;
  for (int it = 0; it < 6; ++it) {
    double num = 0, den = 0;
    for (const auto& o : octs) {
      const double w = o.n / ((1 + b * o.g) * (1 + b * o.g));
      num += w * o.g * (o.e - 1.0);
      den += w * o.g * o.g;
    }
    b = den > 0 ? std::max(0.0, num / den) : 0.0;
  }
  double lr = 0;
  for (std::size_t i = 0; i < zeta.size(); ++i) {
    const double k = 1 + b * g[i];
    lr += zeta[i] - std::log(k) - zeta[i] / k;
  }
  d.pink_b = b;
  d.pink_delta_2lnl = 2 * lr;
  d.pink = b > 0 && 2 * lr > kPinkLr;
  if (d.pink) {
    double v = 0;  // the 1/f part's variance in the filtered residual, σ² units
    for (std::size_t j = 1; j <= half && j < static_cast<std::size_t>(shape.size()); ++j)
      v += (2 * j == static_cast<std::size_t>(m) ? 1.0 : 2.0) * shape[Eigen::Index(j)] / total * b / double(j);
    d.pink_rms_v = sigma * std::sqrt(v);
  }
  return d;
}

OeBaseline report_disturbances(const DisturbanceModel& d, const PinkFilter* pink, const Eigen::MatrixXd& columns,
                               Problem& prob, const Averaged& rec, const std::vector<cd>& t, double sigma,
                               double s2) {
  OeBaseline out;
  out.modelled = d.baseline;
  out.delta_chi2 = d.baseline_delta_chi2;
  out.dof = d.baseline_dof;
  out.log10_p = d.baseline_log10_p;
  out.poly_degree = d.baseline ? d.poly_degree : 0;
  out.mains_hz = d.baseline && d.harmonics > 0 ? d.mains_hz : 0.0;
  out.mains_known = d.mains_known;
  out.mains_distinguishable = d.mains_distinguishable;
  out.harmonics = d.baseline ? d.harmonics : 0;
  out.pink = d.pink;
  out.pink_ratio = d.pink_b;
  out.pink_rms_v = d.pink_rms_v;
  out.pink_delta_2lnl = d.pink_delta_2lnl;
  out.transfer_error_chi2 = d.transfer_error_chi2;
  out.channel_offsets = rec.with_offsets;
  for (int c = 0; c < 2; ++c) {
    out.channel_offset_v[c] = rec.offset_v[c];
    out.channel_offset_sigma_v[c] = rec.offset_sigma_v[c];
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  out.slope_v_per_s = out.slope_sigma_v_per_s = nan;
  if (columns.cols() == 0 || !(sigma > 0)) {
    out.offset_v = out.offset_sigma_v = nan;
    return out;
  }
  auto whiten = [&](const Eigen::VectorXd& v) -> Eigen::VectorXd { return pink ? (*pink)(v) : v; };
  Eigen::MatrixXd cw(columns.rows(), columns.cols());
  for (Eigen::Index c = 0; c < columns.cols(); ++c) cw.col(c) = whiten(columns.col(c));
  const Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(cw);
  const Eigen::MatrixXd cov = sigma * sigma * s2 * (cw.transpose() * cw).completeOrthogonalDecomposition().pseudoInverse();
  const Eigen::VectorXd r = prob.residual_of(t);
  const double seconds = double(rec.v1.size()) / prob.sample_rate_hz();
  const Eigen::Index nc = columns.cols();
  // hum's fundamental: the first cos/sin pair after the polynomial
  // (only when the fundamental itself is in the columns: a record of 5–10 ms
  // at 50 Hz holds the 2nd and 3rd harmonics' half cycle but not its own)
  const bool fundamental = d.mains_hz * seconds >= 0.5;
  const Eigen::Index hum0 =
      d.baseline && d.harmonics > 0 && fundamental && nc >= d.poly_degree + 3 ? d.poly_degree + 1 : -1;
  auto hum_of = [&](const Eigen::VectorXd& c) { return hum0 >= 0 ? std::hypot(c[hum0], c[hum0 + 1]) : nan; };
  const Eigen::VectorXd c = cod.solve(whiten(r));
  out.offset_v = c[0];
  out.offset_sigma_v = std::sqrt(std::max(0.0, cov(0, 0)));
  if (nc > 1 && d.baseline) {
    // P1 = 2t/T − 1: the slope of a unit coefficient is 2/T.
    out.slope_v_per_s = c[1] * 2.0 / seconds;
    out.slope_sigma_v_per_s = std::sqrt(std::max(0.0, cov(1, 1))) * 2.0 / seconds;
  }
  if (hum0 >= 0) {
    out.hum_v = hum_of(c);
    Eigen::Vector2d g(c[hum0], c[hum0 + 1]);
    if (out.hum_v > 0) g /= out.hum_v;
    else g = Eigen::Vector2d(std::sqrt(0.5), std::sqrt(0.5));
    out.hum_sigma_v = std::sqrt(std::max(0.0, g.dot(cov.block(hum0, hum0, 2, 2) * g)));
  }
  for (std::size_t k = 0; rec.shots >= 2 && k < rec.dev1.size(); ++k) {
    const Eigen::VectorXd ck = cod.solve(whiten(r + prob.deviation(t, rec.dev1[k], rec.dev2[k])));
    OeBaselineShot s;
    s.shot = static_cast<int>(k);
    s.offset_v = ck[0];
    s.slope_v_per_s = nc > 1 && d.baseline ? ck[1] * 2.0 / seconds : nan;
    s.hum_v = hum_of(ck);
    out.shots.push_back(s);
  }
  return out;
}

}  // namespace piezo::update::oe
