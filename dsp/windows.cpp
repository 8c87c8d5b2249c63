#include "dsp/windows.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace piezo::dsp {

Eigen::VectorXd make_window(const Window& w, Eigen::Index n) {
  if (n <= 0) throw std::invalid_argument("make_window: length must be positive");
  Eigen::VectorXd out(n);
  const double two_pi = 2.0 * std::numbers::pi;
  for (Eigen::Index i = 0; i < n; ++i) {
    const double x = static_cast<double>(i) / static_cast<double>(n);  // periodic
    double v = 1.0;
    switch (w.kind) {
      case WindowKind::Rectangular: v = 1.0; break;
      case WindowKind::Hann: v = 0.5 - 0.5 * std::cos(two_pi * x); break;
      case WindowKind::Hamming: v = 0.54 - 0.46 * std::cos(two_pi * x); break;
      case WindowKind::BlackmanHarris:
        v = 0.35875 - 0.48829 * std::cos(two_pi * x) + 0.14128 * std::cos(2 * two_pi * x) -
            0.01168 * std::cos(3 * two_pi * x);
        break;
      case WindowKind::FlatTop:
        v = 0.21557895 - 0.41663158 * std::cos(two_pi * x) + 0.277263158 * std::cos(2 * two_pi * x) -
            0.083578947 * std::cos(3 * two_pi * x) + 0.006947368 * std::cos(4 * two_pi * x);
        break;
      case WindowKind::Tukey: {
        const double a = std::clamp(w.param, 0.0, 1.0);
        if (a <= 0.0) { v = 1.0; break; }
        if (x < a / 2) v = 0.5 * (1 - std::cos(two_pi * x / a));
        else if (x > 1 - a / 2) v = 0.5 * (1 - std::cos(two_pi * (1 - x) / a));
        else v = 1.0;
        break;
      }
      case WindowKind::Exponential:
        if (w.param < 0) throw std::invalid_argument("make_window: exponential decay must be >= 0");
        v = std::exp(-w.param * static_cast<double>(i) / std::max<double>(1.0, double(n - 1)));
        break;
    }
    out[i] = v;
  }
  return out;
}

std::string_view to_string(WindowKind k) {
  switch (k) {
    case WindowKind::Rectangular: return "rect";
    case WindowKind::Hann: return "hann";
    case WindowKind::Hamming: return "hamming";
    case WindowKind::BlackmanHarris: return "blackman-harris";
    case WindowKind::FlatTop: return "flattop";
    case WindowKind::Tukey: return "tukey";
    case WindowKind::Exponential: return "exponential";
  }
  return "?";
}

std::optional<WindowKind> parse_window(std::string_view s) {
  for (auto k : {WindowKind::Rectangular, WindowKind::Hann, WindowKind::Hamming,
                 WindowKind::BlackmanHarris, WindowKind::FlatTop, WindowKind::Tukey,
                 WindowKind::Exponential})
    if (s == to_string(k)) return k;
  return std::nullopt;
}

Eigen::VectorXd blackman_lowpass(double fs, double fc) {
  constexpr double kTwoPi = 2.0 * M_PI;
  const auto taps = static_cast<Eigen::Index>(2 * std::ceil(5.5 * fs / fc) + 1);
  const double f = fc / fs;
  const double mid = double(taps - 1) / 2.0;
  Eigen::VectorXd h(taps);
  for (Eigen::Index k = 0; k < taps; ++k) {
    const double t = double(k) - mid;
    const double sinc = t == 0.0 ? 2.0 * f : std::sin(kTwoPi * f * t) / (M_PI * t);
    const double w = 0.42 - 0.5 * std::cos(kTwoPi * double(k) / double(taps - 1)) +
                     0.08 * std::cos(2.0 * kTwoPi * double(k) / double(taps - 1));
    h[k] = sinc * w;
  }
  return h / h.sum();
}

}  // namespace piezo::dsp
