#pragma once
// Prony-SS complex exponential decomposition (seed §4.3.2, after Hu et al. 2013,
// 2016): one or several signals y_j(t_k), t_k = kΔt, are fitted as
//     y_j(t_k) = Σ_n γ_{n,j} z_n^k,   z_n = e^{λ_n Δt}          (eqs 118, 145)
// with one set of global poles λ_n shared by all signals. Steps:
//   1. block-Hankel H(0), H(1) (eqs 135, 147), SVD of H(0) (eqs 141, 154),
//      model order p from the singular values (noise rejection, eqs 162-163);
//   2. realization A = Σ1^-1/2·U1ᵀ·H(1)·V1·Σ1^-1/2 (eqs 143, 151), z_n = eig(A),
//      λ_n = ln(z_n)/Δt (eq. 164);
//   3. residues γ by least squares on the Vandermonde system (eqs 144, 155).
// The Laplace transform of the fitted signal is Σ γ_n/(s − λ_n) (eq. 114).
#include <Eigen/Core>
#include <complex>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "dsp/impedance_types.hpp"

namespace piezo::dsp {

enum class SvdMethod {
  Auto,        // Full for small Hankel matrices, Randomized otherwise
  Full,        // dense H(0), Eigen::BDCSVD: every singular value
  Randomized,  // FFT-based Hankel products + randomized range finder (Halko et al. 2011)
};

// How the automatic order is read off the singular values of H(0).
enum class OrderRule {
  // The noise floor (eqs 162-163): see noise_threshold below (the default).
  NoiseFloor,
  // The seed's §5.1.2 rule: the largest drop s_p/s_{p+1} among the first
  // max_order + 1 singular values (its Fig. 27: "a significant gap between its
  // 26th and 27th singular values ... the model order is set equal to 26").
  // Needs no noise level; see largest_drop_order().
  LargestDrop,
};

struct PronyOptions {
  std::size_t rows = 0;  // ξ, block rows of H(0); 0: half of the samples used
  std::size_t cols = 0;  // η; 0: samples − ξ (the most H(1) allows)
  std::optional<std::size_t> order;  // manual model order p; empty: automatic
  std::size_t max_order = 60;        // automatic order never exceeds this
  // Automatic order (noise rejection, eqs 162-163): the gap between system and
  // noise components is placed where the singular values of the data meet the
  // largest singular value of the same Hankel matrix built from simulated white
  // noise at the data's noise level: p = #{s_k > noise_threshold·s_noise}
  // (and s_k > 1e-12·s_1, the numerical floor of noise-free data).
  double noise_threshold = 1.25;
  OrderRule order_rule = OrderRule::NoiseFloor;
  // Noise model: signal noise = noise_mixing · w, w iid N(0, 1) (m × q). Empty:
  // independent noise per signal with the std from estimate_noise_std().
  Eigen::MatrixXd noise_mixing;
  SvdMethod svd = SvdMethod::Auto;
  std::size_t oversampling = 20;     // randomized SVD: extra sketch columns
  std::size_t power_iterations = 2;  // randomized SVD: subspace iterations
  std::uint64_t seed = 12345;        // randomized SVD: sketch seed (deterministic)
  // Samples right after t = 0 left out of the Hankel matrices and the residue fit
  // (e.g. the anti-alias filter's smear of a drive step); the residues still
  // refer to t = 0, since the model z_n^k holds for every k >= 0.
  std::size_t skip_samples = 0;
  bool normalize_signals = true;  // scale each signal to unit RMS before stacking
  // Decimation D of the Hankel step for heavily oversampled data: each signal is
  // low-pass filtered (windowed-sinc FIR, cutoff 0.8·fs/2D, 10·D + 1 taps; its
  // output from sample 10·D on is exactly Σ γ_n H(z_n) z_n^k, same poles) and
  // every D-th sample kept; poles come from the decimated Hankel matrices and the
  // residues from the full-rate samples (eq. 155), so nothing is aliased into Z.
  // 0: automatic, D = max(1, floor(fs / (5·band_hz))) (1 without band_hz).
  std::size_t decimation = 0;
  double band_hz = 0.0;  // highest frequency of interest (for decimation = 0)
};

struct PronyFit {
  double dt = 0.0;
  std::size_t order = 0;
  bool order_automatic = true;
  Eigen::VectorXd singular_values;  // of H(0) (signals as stacked), descending, as computed
  double noise_singular_value = 0;  // largest singular value of the simulated-noise H(0)
  Eigen::VectorXcd z;               // eigenvalues of A (eq. 143)
  Eigen::VectorXcd lambda;          // λ_n = ln(z_n)/Δt (eq. 164), 1/s
  Eigen::MatrixXcd residues;        // order × signals: γ_{n,j} (eq. 155), referred to t = 0
  Eigen::VectorXd residual_rms;     // per signal, over the samples fitted
  Eigen::Index samples = 0;         // samples used (from t = 0)
  std::size_t decimation = 1;       // D used for the Hankel step
};

// y: K × m, one signal per column, sample 0 at t = 0. Throws std::invalid_argument
// for a non-positive rate, non-finite or constant signals, a Hankel matrix too
// small for the (manual) order, or too few samples.
PronyFit prony_ss(const Eigen::Ref<const Eigen::MatrixXd>& y, double sample_rate_hz,
                  const PronyOptions& opt = {});

// Fits of the same data at several orders from ONE Hankel SVD (the
// stabilization chart's rows): the realization of order p is the leading
// p × p block of the largest one's, so each extra order costs an eigenvalue
// problem and a residue fit, not a decomposition. An order of 0 is the
// automatic one; opt.order is ignored. Errors of the data as a whole (bad
// rate, constant signal, too few samples) throw std::invalid_argument; an
// order the data cannot carry is that entry's `error`.
struct PronyOrderFit {
  std::size_t requested = 0;
  std::optional<PronyFit> fit;
  std::string error;  // when !fit
};
std::vector<PronyOrderFit> prony_ss_orders(const Eigen::Ref<const Eigen::MatrixXd>& y,
                                           double sample_rate_hz, const PronyOptions& opt,
                                           const std::vector<std::size_t>& orders);

// The decimation D prony_ss uses for `opt` at this rate (opt.decimation, or
// the automatic choice from band_hz); 10·D + 1 is its low-pass filter's length.
std::size_t decimation_factor(const PronyOptions& opt, double sample_rate_hz);

// The automatic order rule on descending singular values s given the noise
// Hankel's largest singular value.
std::size_t select_order(const Eigen::VectorXd& s, double s_noise, std::size_t max_order,
                         double noise_threshold);

// The seed's rule (OrderRule::LargestDrop): the p in 1..min(max_order, size−1)
// with the largest ratio s_p/s_{p+1} (1-based; s descending; values below
// 1e-13·s_1, the SVD's rounding, count as 1e-13·s_1, so a numerically
// rank-deficient H(0) drops at its numerical rank). Throws std::invalid_argument for fewer than 2 values or s_1 <= 0.
std::size_t largest_drop_order(const Eigen::VectorXd& s, std::size_t max_order);

// Robust white-noise std of an oversampled signal: MAD of the 6th differences
// (C(12,6)·σ² for white noise), blind to steps and to content well below Nyquist.
double estimate_noise_std(const Eigen::Ref<const Eigen::VectorXd>& x);

// Y_j(s) = Σ_n γ_{n,j}/(s − λ_n) (eq. 114).
std::complex<double> laplace(const PronyFit& fit, Eigen::Index signal, std::complex<double> s);

// The fitted model sampled at k = 0..samples−1 (samples × m).
Eigen::MatrixXd reconstruct(const PronyFit& fit, Eigen::Index samples);

// Poles with Im λ >= 0, by frequency: f = Im λ/2π, ξ = −Re λ/|λ| (eqs 164-165).
std::vector<PoleInfo> pole_table(const PronyFit& fit);

}  // namespace piezo::dsp
