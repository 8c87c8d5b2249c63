#include "dsp/hankel.hpp"

#include <stdexcept>

#include "dsp/fft.hpp"

namespace piezo::dsp {

BlockHankel::BlockHankel(const Eigen::Ref<const Eigen::MatrixXd>& y, Eigen::Index rows,
                         Eigen::Index cols)
    : y_(y), m_(y.cols()), xi_(rows), eta_(cols) {
  if (m_ < 1) throw std::invalid_argument("BlockHankel: no signal");
  if (rows < 1 || cols < 1) throw std::invalid_argument("BlockHankel: rows and cols must be >= 1");
  if (rows + cols > y.rows())
    throw std::invalid_argument("BlockHankel: rows + cols = " + std::to_string(rows + cols) +
                                " exceeds the " + std::to_string(y.rows()) +
                                " samples (H(1) needs rows + cols <= samples)");
  nfft_ = good_fft_size(static_cast<std::size_t>(rows + cols - 1));
}

BlockHankel::~BlockHankel() = default;

Eigen::MatrixXd BlockHankel::dense(int shift) const {
  Eigen::MatrixXd h(rows(), eta_);
  for (Eigen::Index j = 0; j < m_; ++j)
    for (Eigen::Index c = 0; c < eta_; ++c)
      h.col(c).segment(j * xi_, xi_) = y_.col(j).segment(shift + c, xi_);
  return h;
}

const Eigen::MatrixXcd& BlockHankel::spectra(int shift) const {
  if (!have_spec_[shift]) {
    if (!fft_) const_cast<BlockHankel*>(this)->fft_ = std::make_unique<RealFft>(nfft_);
    const Eigen::Index bins = static_cast<Eigen::Index>(fft_->bins());
    spec_[shift].resize(bins, m_);
    Eigen::VectorXd seg;
    for (Eigen::Index j = 0; j < m_; ++j) {
      seg = y_.col(j).segment(shift, xi_ + eta_ - 1);
      fft_->forward(seg.data(), static_cast<std::size_t>(seg.size()), spec_[shift].col(j).data());
    }
    have_spec_[shift] = true;
  }
  return spec_[shift];
}

// Σ_c s[r + c]·x[c] is the circular correlation IFFT(S·conj(X))[r], exact for
// r + c < nfft, which nfft >= ξ + η − 1 guarantees.
Eigen::MatrixXd BlockHankel::apply(int shift, const Eigen::MatrixXd& x) const {
  if (x.rows() != eta_) throw std::invalid_argument("BlockHankel::apply: x has wrong row count");
  const auto& s = spectra(shift);
  const Eigen::Index bins = s.rows();
  const double scale = 1.0 / static_cast<double>(nfft_);
  Eigen::MatrixXd out(rows(), x.cols());
  Eigen::VectorXcd xf(bins), prod(bins);
  Eigen::VectorXd col, res(xi_);
  for (Eigen::Index c = 0; c < x.cols(); ++c) {
    col = x.col(c);
    fft_->forward(col.data(), static_cast<std::size_t>(eta_), xf.data());
    for (Eigen::Index j = 0; j < m_; ++j) {
      prod = s.col(j).cwiseProduct(xf.conjugate());
      fft_->inverse(prod.data(), res.data(), static_cast<std::size_t>(xi_));
      out.col(c).segment(j * xi_, xi_) = res * scale;
    }
  }
  return out;
}

Eigen::MatrixXd BlockHankel::apply_transpose(int shift, const Eigen::MatrixXd& w) const {
  if (w.rows() != rows())
    throw std::invalid_argument("BlockHankel::apply_transpose: w has wrong row count");
  const auto& s = spectra(shift);
  const Eigen::Index bins = s.rows();
  const double scale = 1.0 / static_cast<double>(nfft_);
  Eigen::MatrixXd out(eta_, w.cols());
  Eigen::VectorXcd wf(bins), acc(bins);
  Eigen::VectorXd seg, res(eta_);
  for (Eigen::Index c = 0; c < w.cols(); ++c) {
    acc.setZero();
    for (Eigen::Index j = 0; j < m_; ++j) {
      seg = w.col(c).segment(j * xi_, xi_);
      fft_->forward(seg.data(), static_cast<std::size_t>(xi_), wf.data());
      acc += s.col(j).cwiseProduct(wf.conjugate());
    }
    fft_->inverse(acc.data(), res.data(), static_cast<std::size_t>(eta_));
    out.col(c) = res * scale;
  }
  return out;
}

}  // namespace piezo::dsp
