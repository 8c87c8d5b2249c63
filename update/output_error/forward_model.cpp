// Problem's forward model (forward_model.hpp): the filtered, decimated output
// error of a parameter vector, the shots' deviations, the residual's noise
// shape and spectrum, T(f_k) of a port model. The port models themselves
// (cache, second solver, tangent) are port_cache.cpp's.
#include "update/output_error/forward_model.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "dsp/windows.hpp"
#include "model/bench_response.hpp"
#include "numerics/simd_clones.hpp"

namespace piezo::update::oe {

namespace {
// e = t·a − b over n bins (the complex arrays as (re, im) pairs): the
// residual's spectrum, element-wise, as std::complex's product for finite
// parts without its NaN branch; in SIMD clones (numerics/simd_clones.hpp).
PIEZO_SIMD_CLONES void times_minus(const double* __restrict t, const double* __restrict a, const double* __restrict b,
                                   double* __restrict e, std::size_t n) {
  for (std::size_t k = 0; k < n; ++k) {
    const double tr = t[2 * k], ti = t[2 * k + 1], ar = a[2 * k], ai = a[2 * k + 1];
    e[2 * k] = (tr * ar - ti * ai) - b[2 * k];
    e[2 * k + 1] = (tr * ai + ti * ar) - b[2 * k + 1];
  }
}
const double* parts(const std::vector<cd>& z) { return reinterpret_cast<const double*>(z.data()); }
}  // namespace

Problem::Problem(model::ModalSolver& solver, const MaterialClass& cls, const Coordinates5& co,
                 const Averaged& rec, const OeData& data, double band_hz,
                 const model::ModalOptions& modal, const std::shared_ptr<OeRecordShare>& share)
    : solver_(solver), cls_(cls), co_(co), modal_(modal), r1_(data.circuit.r1_ohm),
      fs_(data.sample_rate_hz), band_hz_(band_hz), n_(rec.v1.size()),
      nfft_(dsp::good_fft_size(std::max<std::size_t>(4 * n_, 1u << 14))), fft_(nfft_) {
  fx_.series_resistance_ohm = data.circuit.r_lead_ohm;
  fx_.parallel_capacitance_f = data.circuit.c_parallel_f;
  fx_.daq_input_resistance_ohm = data.circuit.r_daq_ohm;
  fx_.channel_skew_s = data.v2_delay_s;
  fx_.mass_loading = modal_.end_mass_fraction;
  kmax_ = std::min<std::size_t>(fft_.bins() - 1,
                                static_cast<std::size_t>(std::ceil(2.5 * band_hz * double(nfft_) / fs_)));
  decim_ = std::max<std::size_t>(1, static_cast<std::size_t>(fs_ / (2.0 * band_hz)));
  for (std::size_t i = 0; i < n_; i += decim_) idx_.push_back(i);
  const std::array<double, 5> shape{double(n_), fs_, double(nfft_), band_hz_, double(decim_)};
  std::unique_lock<std::mutex> lock;
  if (share) {
    lock = std::unique_lock<std::mutex>(share->mutex);
    const auto& sp = share->spectra;
    if (sp && sp->shape == shape && sp->v1 == rec.v1 && sp->v2 == rec.v2) {
      l_ = sp->l;
      lv1_ = sp->lv1;
      ly_ = sp->ly;
      dinv_.emplace(*sp->dinv);  // (its chirp and kernel; a buffer of its own)
    }
  }
  if (l_.empty()) {
    const Eigen::VectorXd h = dsp::blackman_lowpass(fs_, band_hz);
    if (static_cast<std::size_t>(h.size()) > nfft_ - n_) fail("record too short for the band");
    std::vector<cd> hl(fft_.bins()), v1(fft_.bins()), v2(fft_.bins());
    fft_.forward(h.data(), static_cast<std::size_t>(h.size()), hl.data());
    fft_.forward(rec.v1.data(), n_, v1.data());
    fft_.forward(rec.v2.data(), n_, v2.data());
    lv1_.resize(kmax_ + 1);
    ly_.resize(kmax_ + 1);
    l_.resize(kmax_ + 1);
    for (std::size_t k = 0; k <= kmax_; ++k) {
      l_[k] = hl[k];
      lv1_[k] = hl[k] * v1[k];
      ly_[k] = hl[k] * v2[k];
    }
    dinv_.emplace(nfft_, kmax_, decim_, idx_.size());
    if (share && !share->spectra)
      share->spectra = std::make_shared<const OeRecordShare::Spectra>(OeRecordShare::Spectra{
          shape, rec.v1, rec.v2, l_, lv1_, ly_, std::make_shared<const dsp::DecimatedInverse>(*dinv_)});
  }
  if (lock.owns_lock()) lock.unlock();
  spec_.assign(kmax_ + 1, cd(0.0, 0.0));
  buf_.resize(idx_.size());
  cache_.reserve(kCache);
}

std::optional<std::vector<cd>> Problem::transfer(const Eigen::VectorXd& x,
                                                 const model::EffectSet& fx) {
  const model::ModalPortModel* pp = port_of(x, fx.mass_loading);
  if (!pp) return std::nullopt;
  return transfer_of(*pp, co_.beta(x), co_.eta(x), fx);
}

Eigen::VectorXd Problem::residual_of(const std::vector<cd>& t) {
  times_minus(parts(t), parts(lv1_), parts(ly_), reinterpret_cast<double*>(spec_.data()), kmax_ + 1);
  return invert();
}

std::optional<Eigen::VectorXd> Problem::residual(const Eigen::VectorXd& x) {
  const auto t = transfer(x);
  if (!t) return std::nullopt;
  return residual_of(*t);
}

const std::vector<cd>& Problem::spectrum_of(const std::vector<double>& record, std::vector<cd>& scratch) {
  const bool zero = std::all_of(record.begin(), record.begin() + static_cast<std::ptrdiff_t>(n_),
                                [](double v) { return v == 0.0; });
  if (zero) {  // (the same FFT of the same samples: the same bins, whichever thread makes them)
    std::call_once(columns_->zero_once, [&] {
      columns_->zero_bins.resize(fft_.bins());
      fft_.forward(record.data(), n_, columns_->zero_bins.data());
    });
    return columns_->zero_bins;
  }
  scratch.resize(fft_.bins());
  fft_.forward(record.data(), n_, scratch.data());
  return scratch;
}

Eigen::VectorXd Problem::deviation(const std::vector<cd>& t, const std::vector<double>& d1,
                                   const std::vector<double>& d2) {
  std::vector<cd> sa, sb;
  const std::vector<cd>& a = spectrum_of(d1, sa);
  const std::vector<cd>& b = spectrum_of(d2, sb);
  for (std::size_t k = 0; k <= kmax_; ++k) spec_[k] = l_[k] * (t[k] * a[k] - b[k]);
  return invert();
}

Eigen::VectorXd Problem::residual_psd(const std::vector<cd>& t, double s1, double s2) const {
  const std::size_t m = idx_.size();
  const double fs_dec = fs_ / double(decim_);
  Eigen::VectorXd p = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(m / 2 + 1));
  auto at = [&](double f) {
    const auto k = static_cast<std::size_t>(std::lround(f * double(nfft_) / fs_));
    return k <= kmax_ ? std::norm(l_[k]) * (s1 * s1 * std::norm(t[k]) + s2 * s2) : 0.0;
  };
  for (std::size_t j = 0; j <= m / 2; ++j) {
    const double f = double(j) * fs_dec / double(m);
    double v = 0;
    for (int a = 0; a < 8; ++a) {
      v += at(f + a * fs_dec);
      if (a > 0) v += at(a * fs_dec - f);
    }
    p[static_cast<Eigen::Index>(j)] = v;
  }
  return p;
}

std::optional<ResidualSpectrum> Problem::residual_spectrum(const Eigen::VectorXd& x,
                                                           const model::EffectSet& fx, double s1,
                                                           double s2) {
  const model::ModalPortModel* pp = port_of(x, fx.mass_loading);
  if (!pp) return std::nullopt;
  const model::RayleighDamping damp{0.0, co_.beta(x)};
  const std::size_t r = std::max<std::size_t>(1, static_cast<std::size_t>(std::lround(double(nfft_) / double(n_))));
  double lmax = 0;
  for (std::size_t k = 0; k <= kmax_; ++k) lmax = std::max(lmax, std::abs(l_[k]));
  ResidualSpectrum s;
  for (std::size_t k = 2 * r; k <= kmax_; k += r) {
    if (std::abs(l_[k]) < 0.5 * lmax) continue;
    const double w = kTwoPi * fs_ * double(k) / double(nfft_);
    const cd y = model::tube_admittance(*pp, damp, fx, w, co_.eta(x));
    const cd t = model::recorded_transfer(y, fx, r1_, w);
    const cd dy = 1e-6 * std::abs(y);
    const cd dt = (model::recorded_transfer(y + dy, fx, r1_, w) - t) / dy;
    const double var = double(n_) * std::norm(l_[k]) * (s1 * s1 * std::norm(t) + s2 * s2);
    if (!(var > 0) || !std::isfinite(var)) continue;
    s.f_hz.push_back(w / kTwoPi);
    s.e.push_back(t * lv1_[k] - ly_[k]);
    s.lv1.push_back(lv1_[k]);
    s.t.push_back(t);
    s.dt_dy.push_back(dt);
    s.y_tube.push_back(y);
    s.var.push_back(var);
  }
  return s;
}

double Problem::propagated_sigma(const std::vector<cd>& t, double s1, double s2) const {
  double a1 = 0, a2 = 0;
  for (std::size_t k = 0; k <= kmax_; ++k) {
    const double w = (k == 0 || 2 * k == nfft_) ? 1.0 : 2.0;
    a1 += w * std::norm(l_[k] * t[k]);
    a2 += w * std::norm(l_[k]);
  }
  return std::sqrt((s1 * s1 * a1 + s2 * s2 * a2) / double(nfft_));
}

std::vector<cd> Problem::transfer_of(const model::ModalPortModel& port, double beta, double eta,
                                     const model::EffectSet& fx) const {
  const model::RayleighDamping damp{0.0, beta};
  std::vector<cd> t(kmax_ + 1);
  // The bins' ω (bin 0, ω = 0: no admittance), their admittances in one pass
  // (model::tube_admittances), then the circuit per bin.
  thread_local std::vector<double> w;
  w.resize(kmax_ + 1);
  for (std::size_t k = 0; k <= kmax_; ++k) w[k] = kTwoPi * fs_ * double(k) / double(nfft_);
  std::size_t first = 0;
  while (first <= kmax_ && !(w[first] > 0)) t[first++] = cd(0.0, 0.0);
  model::tube_admittances(port, damp, fx, std::span<const double>(w).subspan(first), eta,
                          std::span<cd>(t).subspan(first));
  model::recorded_transfers(t, fx, r1_, w);
  return t;
}

void Problem::share_columns(const std::shared_ptr<OeRecordShare>& share) {
  if (!share) return;
  const std::array<double, 5> mine{double(n_), fs_, double(nfft_), band_hz_, double(decim_)};
  std::lock_guard<std::mutex> lock(share->mutex);
  if (!share->shape) share->shape = mine;
  if (*share->shape == mine) columns_ = share;
}

Eigen::VectorXd Problem::kept_column(const ColumnKey& key, const std::function<Eigen::VectorXd()>& make) {
  std::lock_guard<std::mutex> lock(columns_->mutex);
  auto it = columns_->columns.find(key);
  if (it == columns_->columns.end()) it = columns_->columns.emplace(key, make()).first;
  return it->second;
}

Eigen::VectorXd Problem::invert() {
  // Only the kept samples idx_ = 0, decim_, 2·decim_, … of the nfft_-point
  // inverse (a chirp-z transform of the kmax_ + 1 bins: dsp/decimated_inverse.hpp;
  // the full real inverse of nfft_ points, every sample but these dropped, was
  // a quarter of a replay's time).
  (*dinv_)(spec_.data(), buf_.data());
  Eigen::VectorXd r(static_cast<Eigen::Index>(idx_.size()));
  const double scale = 1.0 / double(nfft_);
  for (std::size_t i = 0; i < idx_.size(); ++i) r[static_cast<Eigen::Index>(i)] = buf_[i] * scale;
  return r;
}

}  // namespace piezo::update::oe
