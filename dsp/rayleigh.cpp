#include "dsp/rayleigh.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace piezo::dsp {

RayleighDamping rayleigh_from_two_modes(double w1, double xi1, double w2, double xi2) {
  if (!(w1 > 0) || !(w2 > 0) || w1 == w2)
    throw std::invalid_argument("rayleigh_from_two_modes: need two distinct positive frequencies");
  RayleighDamping d;
  d.alpha = (2.0 * xi1 * w1 * w2 * w2 - 2.0 * xi2 * w1 * w1 * w2) / (w2 * w2 - w1 * w1);  // eq. 168
  d.beta = (2.0 * xi1 * w1 - 2.0 * xi2 * w2) / (w1 * w1 - w2 * w2);                      // eq. 169
  return d;
}

RayleighDamping rayleigh_fit(std::span<const PoleInfo> modes) {
  if (modes.size() < 2) throw std::invalid_argument("rayleigh_fit: need at least 2 modes");
  const auto n = static_cast<Eigen::Index>(modes.size());
  Eigen::MatrixXd a(n, 2);
  Eigen::VectorXd b(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    const double w = 2.0 * std::numbers::pi * modes[static_cast<std::size_t>(k)].freq_hz;
    if (!(w > 0)) throw std::invalid_argument("rayleigh_fit: mode frequencies must be positive");
    a.row(k) << 0.5 / w, 0.5 * w;
    b[k] = modes[static_cast<std::size_t>(k)].damping_ratio;
  }
  const Eigen::Vector2d x = a.colPivHouseholderQr().solve(b);
  return {x[0], x[1]};
}

double rayleigh_damping_ratio(const RayleighDamping& d, double w) {
  return 0.5 * (d.alpha / w + d.beta * w);
}

}  // namespace piezo::dsp
