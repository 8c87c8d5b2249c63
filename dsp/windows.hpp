#pragma once
// Data windows for the FFT-based estimators (fft_ratio, cross_spectra).
#include <Eigen/Core>
#include <string_view>
#include <optional>

namespace piezo::dsp {

enum class WindowKind { Rectangular, Hann, Hamming, BlackmanHarris, FlatTop, Tukey, Exponential };

struct Window {
  WindowKind kind = WindowKind::Rectangular;
  // Tukey: taper fraction in [0, 1]. Exponential: w[n] = exp(−param·n/(N−1)),
  // the usual transient window (its extra damping is removed by nobody: it is
  // meant for comparing, as it biases the damping of the estimate).
  double param = 0.5;
};

// Symmetric-in-DFT-sense ("periodic") window of length n.
Eigen::VectorXd make_window(const Window& w, Eigen::Index n);

// Causal low-pass FIR: Blackman-windowed sinc at cutoff fc (Hz) for rate fs,
// 2·ceil(5.5·fs/fc) + 1 taps, unit DC gain (the output-error fits' filter).
Eigen::VectorXd blackman_lowpass(double fs, double fc);

std::string_view to_string(WindowKind k);
std::optional<WindowKind> parse_window(std::string_view s);

}  // namespace piezo::dsp
