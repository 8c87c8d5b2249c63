#pragma once
// Block-Hankel matrices H(k) of one or several sampled signals (seed eqs 135, 147)
// as an operator: dense assembly for the full SVD, and FFT-based products
// H(k)·X, H(k)ᵀ·W in O(ξ+η) log per column for the randomized SVD.
//
// Row order is signal-major (row j·ξ + r holds signal j shifted by r), a row
// permutation of eq. 147's time-major blocks; it leaves the singular values,
// the right singular vectors and the realization A of eq. 143 unchanged.
#include <Eigen/Core>
#include <complex>
#include <memory>
#include <vector>

namespace piezo::dsp {

class RealFft;

// Not thread-safe: the FFT products share one plan and its buffers.
class BlockHankel {
 public:
  // y: K × m, one signal per column. ξ = `rows` block rows, η = `cols` columns;
  // H(0) and H(1) both need ξ + η ≤ K.
  BlockHankel(const Eigen::Ref<const Eigen::MatrixXd>& y, Eigen::Index rows, Eigen::Index cols);
  ~BlockHankel();
  BlockHankel(const BlockHankel&) = delete;
  BlockHankel& operator=(const BlockHankel&) = delete;

  Eigen::Index block_rows() const { return xi_; }
  Eigen::Index signals() const { return m_; }
  Eigen::Index rows() const { return m_ * xi_; }
  Eigen::Index cols() const { return eta_; }

  Eigen::MatrixXd dense(int shift) const;  // H(shift), shift ∈ {0, 1}
  Eigen::MatrixXd apply(int shift, const Eigen::MatrixXd& x) const;            // H(shift)·x
  Eigen::MatrixXd apply_transpose(int shift, const Eigen::MatrixXd& w) const;  // H(shift)ᵀ·w

 private:
  const Eigen::MatrixXcd& spectra(int shift) const;
  Eigen::MatrixXd y_;
  Eigen::Index m_, xi_, eta_;
  std::size_t nfft_ = 0;
  std::unique_ptr<RealFft> fft_;
  mutable Eigen::MatrixXcd spec_[2];  // FFT of each signal's segment, per shift (lazy)
  mutable bool have_spec_[2] = {false, false};
};

}  // namespace piezo::dsp
