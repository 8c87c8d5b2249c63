#include "dsp/prony_ss.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <memory>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>

#include "dsp/hankel.hpp"
#include "dsp/work_counters.hpp"
#include "numerics/complex_division.hpp"
#include "numerics/simd_clones.hpp"

namespace piezo::dsp {

namespace {

[[noreturn]] void fail(const std::string& msg) {
  throw std::invalid_argument("prony_ss: " + msg);
}

Eigen::MatrixXd orthonormal_basis(const Eigen::MatrixXd& y) {
  Eigen::HouseholderQR<Eigen::MatrixXd> qr(y);
  return qr.householderQ() * Eigen::MatrixXd::Identity(y.rows(), y.cols());
}

struct Svd {
  Eigen::VectorXd s;
  Eigen::MatrixXd u, v;  // leading columns only for the randomized form
};

Svd full_svd(const BlockHankel& h) {
  Eigen::BDCSVD<Eigen::MatrixXd> svd(h.dense(0), Eigen::ComputeThinU | Eigen::ComputeThinV);
  return {svd.singularValues(), svd.matrixU(), svd.matrixV()};
}

// Randomized range finder with subspace iteration (Halko, Martinsson & Tropp
// 2011, algorithms 4.4 and 5.1), all products with H(0) through the FFT.
Svd randomized_svd(const BlockHankel& h, Eigen::Index k, std::size_t power_iterations,
                   std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> nd;
  Eigen::MatrixXd omega(h.cols(), k);
  for (Eigen::Index i = 0; i < omega.size(); ++i) omega.data()[i] = nd(rng);
  Eigen::MatrixXd q = orthonormal_basis(h.apply(0, omega));
  for (std::size_t it = 0; it < power_iterations; ++it) {
    Eigen::MatrixXd w = orthonormal_basis(h.apply_transpose(0, q));
    q = orthonormal_basis(h.apply(0, w));
  }
  Eigen::MatrixXd bt = h.apply_transpose(0, q);  // Bᵀ = H(0)ᵀ Q, η × k
  Eigen::BDCSVD<Eigen::MatrixXd> svd(bt, Eigen::ComputeThinU | Eigen::ComputeThinV);
  // Bᵀ = Ub S Vbᵀ  ⇒  H(0) ≈ Q B = (Q Vb) S Ubᵀ
  return {svd.singularValues(), q * svd.matrixV(), svd.matrixU()};
}

// Windowed-sinc (Blackman) low-pass FIR for decimation by d, unit DC gain.
Eigen::VectorXd decimation_filter(std::size_t d) {
  const auto taps = static_cast<Eigen::Index>(10 * d + 1);
  const double fc = 0.8 / (2.0 * double(d));  // cycles/sample
  const double mid = double(taps - 1) / 2.0;
  Eigen::VectorXd h(taps);
  for (Eigen::Index k = 0; k < taps; ++k) {
    const double x = double(k) - mid;
    const double sinc = x == 0.0 ? 2.0 * fc : std::sin(2.0 * std::numbers::pi * fc * x) / (std::numbers::pi * x);
    const double w = 0.42 - 0.5 * std::cos(2.0 * std::numbers::pi * double(k) / double(taps - 1)) +
                     0.08 * std::cos(4.0 * std::numbers::pi * double(k) / double(taps - 1));
    h[k] = sinc * w;
  }
  return h / h.sum();
}

// Filtered and decimated signals: w[m] = Σ_l h[l]·y[L−1 + m·d − l].
Eigen::MatrixXd decimate(const Eigen::MatrixXd& y, std::size_t d) {
  const Eigen::VectorXd h = decimation_filter(d);
  const Eigen::Index taps = h.size(), D = static_cast<Eigen::Index>(d);
  const Eigen::Index m = (y.rows() - taps) / D + 1;
  Eigen::MatrixXd w(std::max<Eigen::Index>(m, 0), y.cols());
  const Eigen::VectorXd hr = h.reverse();
  for (Eigen::Index j = 0; j < y.cols(); ++j)
    for (Eigen::Index k = 0; k < w.rows(); ++k) w(k, j) = y.col(j).segment(k * D, taps).dot(hr);
  return w;
}

}  // namespace

std::size_t select_order(const Eigen::VectorXd& s, double s_noise, std::size_t max_order,
                         double noise_threshold) {
  if (s.size() < 1 || !(s[0] > 0.0)) throw std::invalid_argument("select_order: the Hankel matrix is zero");
  const double floor = std::max(noise_threshold * s_noise, 1e-12 * s[0]);
  const std::size_t pmax = std::min<std::size_t>(max_order, static_cast<std::size_t>(s.size()));
  std::size_t p = 0;
  while (p < pmax && s[static_cast<Eigen::Index>(p)] > floor) ++p;
  return std::max<std::size_t>(p, 1);
}

std::size_t largest_drop_order(const Eigen::VectorXd& s, std::size_t max_order) {
  if (s.size() < 2 || !(s[0] > 0.0))
    throw std::invalid_argument("largest_drop_order: need two singular values and s_1 > 0");
  const auto last = std::min<Eigen::Index>(static_cast<Eigen::Index>(std::max<std::size_t>(max_order, 1)),
                                           s.size() - 1);
  // Singular values at the SVD's rounding level (below 1e-13·s_1: ~1e3 ulp,
  // what a dense SVD of a few-hundred-square matrix leaves of an exactly
  // rank-deficient one) count as that level: the drop INTO the rounding is the
  // numerical rank, ratios among rounding values mean nothing.
  const double floor = 1e-13 * s[0];
  std::size_t best = 1;
  double best_ratio = 0.0;
  for (Eigen::Index p = 1; p <= last; ++p) {  // drop between s_p and s_{p+1} (1-based)
    const double ratio = std::max(s[p - 1], floor) / std::max(s[p], floor);
    if (ratio > best_ratio) {
      best_ratio = ratio;
      best = static_cast<std::size_t>(p);
    }
  }
  return best;
}

std::size_t decimation_factor(const PronyOptions& opt, double sample_rate_hz) {
  if (opt.decimation > 0) return opt.decimation;
  return opt.band_hz > 0.0 ? std::max<std::size_t>(
                                 1, static_cast<std::size_t>(sample_rate_hz / (5.0 * opt.band_hz)))
                           : 1;
}

namespace {
// |Σ_l c_l x[k + l]| for every k, the binomial sixth difference: term by term
// in l's order for all k at once (each k's sum in the order of the loop it
// replaced, 0 + c_0·x_k + …, so the same bits), in SIMD clones
// (numerics/simd_clones.hpp).
PIEZO_SIMD_CLONES void sixth_differences(const double* __restrict x, double* __restrict d, std::size_t n) {
  constexpr double kBinom[7] = {1, -6, 15, -20, 15, -6, 1};
  for (std::size_t k = 0; k < n; ++k) d[k] = 0.0;
  for (int l = 0; l <= 6; ++l)
    for (std::size_t k = 0; k < n; ++k) d[k] += kBinom[l] * x[k + static_cast<std::size_t>(l)];
  for (std::size_t k = 0; k < n; ++k) d[k] = std::abs(d[k]);
}
}  // namespace

double estimate_noise_std(const Eigen::Ref<const Eigen::VectorXd>& x) {
  constexpr int kOrder = 6;  // (sixth_differences: Σ c² = C(12,6) = 924)
  if (x.size() < 4 * kOrder) throw std::invalid_argument("estimate_noise_std: need at least 24 samples");
  std::vector<double> d(static_cast<std::size_t>(x.size() - kOrder));
  sixth_differences(x.data(), d.data(), d.size());  // (a Ref<const VectorXd>: contiguous)
  std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
  return 1.482602218505602 * d[d.size() / 2] / std::sqrt(924.0);
}

namespace {

// Step 1 of prony_ss for one data set: the scaled (and decimated) signals'
// Hankel matrices and the SVD of H(0), computed once for every order asked of
// them (the realization of order p uses the leading p singular triplets only).
struct Decomposition {
  Eigen::Index k_total = 0, k_used = 0, skip = 0, rank_cap = 0;
  std::size_t dec = 1;
  bool automatic_possible = false;
  double noise_singular_value = 0;  // automatic order only
  std::unique_ptr<BlockHankel> h;
  Svd svd;
  Eigen::MatrixXd h1v;  // H(1)·V over the computed columns, filled on first use
};

Decomposition decompose(const Eigen::Ref<const Eigen::MatrixXd>& y, double sample_rate_hz,
                        const PronyOptions& opt, std::size_t highest_order, bool automatic,
                        bool highest_must_fit) {
  g_prony_decompositions.fetch_add(1, std::memory_order_relaxed);  // dsp/work_counters.hpp
  if (!(sample_rate_hz > 0.0) || !std::isfinite(sample_rate_hz))
    fail("sample rate must be positive");
  const Eigen::Index m = y.cols();
  if (m < 1) fail("no signal");
  if (!y.allFinite()) fail("signals contain NaN or Inf");
  Decomposition d;
  d.skip = static_cast<Eigen::Index>(opt.skip_samples);
  d.k_total = y.rows();
  d.k_used = d.k_total - d.skip;
  const Eigen::Index k_used = d.k_used;
  if (k_used < 8)
    fail("too short: " + std::to_string(d.k_total) + " samples (after skipping " +
         std::to_string(d.skip) + "), need at least 8");

  // Per-signal scaling (to unit RMS) so that volts and amperes weigh alike.
  Eigen::MatrixXd ys = y.bottomRows(k_used);
  Eigen::VectorXd scale = Eigen::VectorXd::Ones(m);
  for (Eigen::Index j = 0; j < m; ++j) {
    const auto col = y.col(j).tail(k_used);
    const double span = col.maxCoeff() - col.minCoeff();
    const double mag = col.cwiseAbs().maxCoeff();
    if (!(span > 1e-12 * mag))
      fail("signal " + std::to_string(j) + " is constant over the " + std::to_string(k_used) +
           " samples: it holds no exponential components to decompose");
    if (opt.normalize_signals) scale[j] = 1.0 / std::sqrt(col.squaredNorm() / double(k_used));
    ys.col(j) *= scale[j];
  }
  if (opt.noise_mixing.size() && opt.noise_mixing.rows() != m)
    fail("noise_mixing must have one row per signal");

  const std::size_t dec = decimation_factor(opt, sample_rate_hz);
  d.dec = dec;
  if (automatic && k_used < 24)
    fail("too short for the automatic order: " + std::to_string(k_used) +
         " samples, need at least 24 (or give the order)");
  // The noise-floor rule compares with simulated noise; the largest-drop rule needs none.
  const bool noise_floor = automatic && opt.order_rule == OrderRule::NoiseFloor;
  Eigen::MatrixXd noise;  // simulated noise, scaled like the data (noise-floor rule only)
  if (noise_floor) {
    Eigen::MatrixXd mix = opt.noise_mixing;
    if (!mix.size()) {
      mix = Eigen::MatrixXd::Zero(m, m);
      for (Eigen::Index j = 0; j < m; ++j) mix(j, j) = estimate_noise_std(y.col(j).tail(k_used));
    }
    std::mt19937_64 rng(opt.seed ^ 0x9e3779b97f4a7c15ULL);
    std::normal_distribution<double> nd;
    Eigen::MatrixXd w(k_used, mix.cols());
    for (Eigen::Index i = 0; i < w.size(); ++i) w.data()[i] = nd(rng);
    noise = w * mix.transpose() * scale.asDiagonal();
  }
  if (dec > 1) {
    ys = decimate(ys, dec);
    if (noise_floor) noise = decimate(noise, dec);
    if (ys.rows() < 8)
      fail("too short for decimation by " + std::to_string(dec) + ": " + std::to_string(k_used) +
           " samples leave " + std::to_string(ys.rows()) + " (need 8); lower band_hz/decimation");
  }
  const Eigen::Index k_hankel = ys.rows();
  const Eigen::Index xi = opt.rows ? static_cast<Eigen::Index>(opt.rows) : k_hankel / 2;
  const Eigen::Index eta = opt.cols ? static_cast<Eigen::Index>(opt.cols) : k_hankel - xi;
  if (xi < 2 || eta < 2 || xi + eta > k_hankel)
    fail("Hankel matrix " + std::to_string(xi) + " x " + std::to_string(eta) +
         " does not fit in " + std::to_string(k_hankel) + " samples (rows + cols <= samples" +
         (dec > 1 ? ", after decimation by " + std::to_string(dec) : std::string()) + ")");
  d.rank_cap = std::min<Eigen::Index>(m * xi, eta) - 1;
  if (static_cast<Eigen::Index>(highest_order) > d.rank_cap) {
    if (highest_must_fit)
      fail("Hankel matrix too small for order " + std::to_string(highest_order) + ": H(0) is " +
           std::to_string(m * xi) + " x " + std::to_string(eta) + ", order must be < " +
           std::to_string(d.rank_cap + 1) + " (give more samples or larger rows/cols)");
    highest_order = static_cast<std::size_t>(std::max<Eigen::Index>(d.rank_cap, 1));
  }

  d.h = std::make_unique<BlockHankel>(ys, xi, eta);
  const BlockHankel& h = *d.h;
  // The sketch is as wide as the highest order asked for needs (the automatic
  // rule may pick up to max_order) plus the oversampling.
  const Eigen::Index want = static_cast<Eigen::Index>(
      std::max<std::size_t>(highest_order, automatic ? opt.max_order : 0) + opt.oversampling);
  SvdMethod method = opt.svd;
  if (method == SvdMethod::Auto)
    method = (double(h.rows()) * double(h.cols()) <= 2.5e5 ||
              want >= std::min(h.rows(), h.cols()) / 2)
                 ? SvdMethod::Full
                 : SvdMethod::Randomized;
  d.svd = method == SvdMethod::Full
              ? full_svd(h)
              : randomized_svd(h, std::min<Eigen::Index>(want, std::min(h.rows(), h.cols())),
                               opt.power_iterations, opt.seed);
  if (!(d.svd.s[0] > 0.0)) fail("the Hankel matrix is zero");
  if (noise_floor) {
    BlockHankel hn(noise, xi, eta);
    d.noise_singular_value =
        randomized_svd(hn, std::min<Eigen::Index>(8, std::min(hn.rows(), hn.cols())), 4, opt.seed).s[0];
  }
  d.automatic_possible = automatic;
  return d;
}

// Steps 2-3 at order p (0: the automatic order) from a decomposition.
PronyFit realize(Decomposition& d, const Eigen::Ref<const Eigen::MatrixXd>& y,
                 double sample_rate_hz, const PronyOptions& opt, std::size_t order) {
  PronyFit fit;
  fit.dt = 1.0 / sample_rate_hz;
  fit.samples = d.k_total;
  fit.decimation = d.dec;
  fit.singular_values = d.svd.s;
  fit.order_automatic = order == 0;
  if (order == 0 && opt.order_rule == OrderRule::LargestDrop) {
    // The seed's rule (§5.1.2); the rank cap keeps the realization's H(1) valid.
    fit.order = largest_drop_order(
        d.svd.s, std::min<std::size_t>(opt.max_order, static_cast<std::size_t>(d.rank_cap)));
  } else if (order == 0) {
    fit.noise_singular_value = d.noise_singular_value;
    fit.order = select_order(d.svd.s, d.noise_singular_value,
                             std::min<std::size_t>(opt.max_order, static_cast<std::size_t>(d.rank_cap)),
                             opt.noise_threshold);
  } else {
    if (static_cast<Eigen::Index>(order) > d.rank_cap)
      fail("Hankel matrix too small for order " + std::to_string(order) + ": H(0) is " +
           std::to_string(d.h->rows()) + " x " + std::to_string(d.h->cols()) +
           ", order must be < " + std::to_string(d.rank_cap + 1) +
           " (give more samples or larger rows/cols)");
    fit.order = order;
  }
  const auto p = static_cast<Eigen::Index>(fit.order);
  if (p > d.svd.s.size()) fail("order exceeds the singular values computed");
  if (!(d.svd.s[p - 1] > 1e-14 * d.svd.s[0]))
    fail("order " + std::to_string(p) + " exceeds the numerical rank of the Hankel matrix (s_p/s_1 = " +
         std::to_string(d.svd.s[p - 1] / d.svd.s[0]) + "): choose a smaller order");

  // Realization (eq. 143): A = Σ1^-1/2 U1ᵀ H(1) V1 Σ1^-1/2; the realization of
  // order p is the leading p × p block of the one over all computed columns.
  if (d.h1v.cols() < p) d.h1v = d.h->apply(1, d.svd.v);  // H(1)·V (FFT product)
  const Eigen::VectorXd sinv = d.svd.s.head(p).cwiseSqrt().cwiseInverse();
  const Eigen::MatrixXd a =
      sinv.asDiagonal() * (d.svd.u.leftCols(p).transpose() * d.h1v.leftCols(p)) * sinv.asDiagonal();
  Eigen::EigenSolver<Eigen::MatrixXd> es(a, false);
  if (es.info() != Eigen::Success) fail("eigenvalues of the realization did not converge");
  fit.z.resize(p);
  fit.lambda.resize(p);
  for (Eigen::Index n = 0; n < p; ++n) {
    const std::complex<double> zd = es.eigenvalues()[n];
    if (std::abs(zd) == 0.0) fail("a pole sits at z = 0 (order too high for the data)");
    fit.lambda[n] = std::log(zd) * (sample_rate_hz / double(d.dec));  // eq. 164 at Δt·D
    fit.z[n] = std::exp(fit.lambda[n] / sample_rate_hz);                // full-rate z
  }

  // Residues (eq. 155) on the unscaled data, columns scaled for conditioning.
  const Eigen::Index k_used = d.k_used;
  Eigen::MatrixXcd vand(k_used, p);
  for (Eigen::Index n = 0; n < p; ++n) {
    const std::complex<double> lz = fit.lambda[n] / sample_rate_hz;
    for (Eigen::Index k = 0; k < k_used; ++k) vand(k, n) = std::exp(lz * double(k + d.skip));
  }
  Eigen::VectorXd cscale = vand.colwise().norm().cwiseInverse().transpose();
  vand = vand * cscale.asDiagonal();
  Eigen::ColPivHouseholderQR<Eigen::MatrixXcd> qr(vand);
  const Eigen::MatrixXcd rhs = y.bottomRows(k_used).cast<std::complex<double>>();
  fit.residues = cscale.asDiagonal() * qr.solve(rhs);
  const Eigen::MatrixXcd res = vand * (cscale.cwiseInverse().asDiagonal() * fit.residues) - rhs;
  fit.residual_rms = (res.colwise().norm() / std::sqrt(double(k_used))).transpose();
  return fit;
}

}  // namespace

PronyFit prony_ss(const Eigen::Ref<const Eigen::MatrixXd>& y, double sample_rate_hz,
                  const PronyOptions& opt) {
  if (opt.order && *opt.order < 1) fail("order must be >= 1");
  Decomposition d = decompose(y, sample_rate_hz, opt, opt.order.value_or(0), !opt.order, true);
  return realize(d, y, sample_rate_hz, opt, opt.order.value_or(0));
}

std::vector<PronyOrderFit> prony_ss_orders(const Eigen::Ref<const Eigen::MatrixXd>& y,
                                           double sample_rate_hz, const PronyOptions& opt,
                                           const std::vector<std::size_t>& orders) {
  std::size_t highest = 0;
  bool automatic = false;
  for (std::size_t p : orders) {
    highest = std::max(highest, p);
    automatic = automatic || p == 0;
  }
  Decomposition d = decompose(y, sample_rate_hz, opt, highest, automatic, false);
  std::vector<PronyOrderFit> out;
  out.reserve(orders.size());
  for (std::size_t p : orders) {
    PronyOrderFit f;
    f.requested = p;
    try {
      f.fit = realize(d, y, sample_rate_hz, opt, p);
    } catch (const std::invalid_argument& e) {
      f.error = e.what();
    }
    out.push_back(std::move(f));
  }
  return out;
}

std::complex<double> laplace(const PronyFit& fit, Eigen::Index signal, std::complex<double> s) {
  // (numerics::divide: libgcc's __divdc3 inlined away, a few ulp — issue 43)
  std::complex<double> acc = 0.0;
  for (Eigen::Index n = 0; n < fit.lambda.size(); ++n)
    acc += numerics::divide(fit.residues(n, signal), s - fit.lambda[n]);
  return acc;
}

Eigen::MatrixXd reconstruct(const PronyFit& fit, Eigen::Index samples) {
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(samples, fit.residues.cols());
  for (Eigen::Index n = 0; n < fit.lambda.size(); ++n) {
    const std::complex<double> lz = fit.lambda[n] * fit.dt;
    for (Eigen::Index k = 0; k < samples; ++k) {
      const std::complex<double> zk = std::exp(lz * double(k));
      for (Eigen::Index j = 0; j < out.cols(); ++j) out(k, j) += (fit.residues(n, j) * zk).real();
    }
  }
  return out;
}

std::vector<PoleInfo> pole_table(const PronyFit& fit) {
  std::vector<PoleInfo> out;
  for (Eigen::Index n = 0; n < fit.lambda.size(); ++n) {
    const auto l = fit.lambda[n];
    if (l.imag() < 0.0) continue;
    const double mag = std::abs(l);
    out.push_back({l, l.imag() / (2.0 * std::numbers::pi), mag > 0 ? -l.real() / mag : 0.0});
  }
  std::sort(out.begin(), out.end(),
            [](const PoleInfo& a, const PoleInfo& b) { return a.freq_hz < b.freq_hz; });
  return out;
}

}  // namespace piezo::dsp
