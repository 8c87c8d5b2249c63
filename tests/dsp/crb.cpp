#include "crb.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace piezo::crb {

double pole_frequency_crb_hz(const std::vector<std::complex<double>>& poles,
                             const std::vector<Channel>& ch, double fs, std::size_t n,
                             std::size_t index) {
  using cd = std::complex<double>;
  const std::size_t np = poles.size(), nc = ch.size();
  // Parameters: per pole (Re λ[, Im λ]) then per channel per pole (Re r[, Im r]).
  std::vector<int> width(np);
  std::vector<std::size_t> lam_at(np), res_at(np);
  std::size_t p = 0;
  for (std::size_t i = 0; i < np; ++i) {
    width[i] = poles[i].imag() > 0 ? 2 : 1;
    lam_at[i] = p;
    p += std::size_t(width[i]);
  }
  for (std::size_t i = 0; i < np; ++i) {
    res_at[i] = p;
    p += nc * std::size_t(width[i]);
  }
  if (poles[index].imag() <= 0) throw std::invalid_argument("pole_frequency_crb_hz: not an oscillating pole");
  Eigen::MatrixXd fisher = Eigen::MatrixXd::Zero(Eigen::Index(p), Eigen::Index(p));
  Eigen::VectorXd row(static_cast<Eigen::Index>(p));
  for (std::size_t c = 0; c < nc; ++c) {
    const double w = 1.0 / (ch[c].sigma * ch[c].sigma);
    for (std::size_t k = 0; k < n; ++k) {
      const double t = double(k) / fs;
      row.setZero();
      for (std::size_t i = 0; i < np; ++i) {
        const cd e = std::exp(poles[i] * t), r = ch[c].residue[i];
        const double m = width[i] == 2 ? 2.0 : 1.0;  // a pair contributes 2·Re(r e^{λt})
        row[Eigen::Index(lam_at[i])] = m * (r * t * e).real();
        if (width[i] == 2) row[Eigen::Index(lam_at[i] + 1)] = m * (cd(0, 1) * r * t * e).real();
        const std::size_t ra = res_at[i] + c * std::size_t(width[i]);
        row[Eigen::Index(ra)] = m * e.real();
        if (width[i] == 2) row[Eigen::Index(ra + 1)] = m * (cd(0, 1) * e).real();
      }
      fisher.noalias() += w * row * row.transpose();
    }
  }
  // Scale to unit diagonal before inverting (time constants and residues differ by decades).
  const Eigen::VectorXd d = fisher.diagonal().cwiseSqrt().cwiseInverse();
  const Eigen::MatrixXd fs_ = d.asDiagonal() * fisher * d.asDiagonal();
  const Eigen::MatrixXd inv = fs_.ldlt().solve(Eigen::MatrixXd::Identity(fs_.rows(), fs_.cols()));
  const Eigen::Index q = Eigen::Index(lam_at[index] + 1);
  return std::sqrt(inv(q, q)) * d[q] / (2.0 * std::numbers::pi);
}

}  // namespace piezo::crb
