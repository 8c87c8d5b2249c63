#include "dsp/uncertainty.hpp"

#include <cmath>
#include <random>
#include <stdexcept>

namespace piezo::dsp {

namespace {
using cd = std::complex<double>;
}

bool ImpedanceBand::covers(Eigen::Index k, cd z) const {
  const double da = std::abs(std::abs(z) - abs_ohm[k]);
  double dp = std::remainder(std::arg(z) - phase_rad[k], 2.0 * M_PI);
  return da <= coverage_factor * abs_sigma_ohm[k] &&
         std::abs(dp) <= coverage_factor * phase_sigma_rad[k];
}

ImpedanceBand band_from_sigma(const Eigen::VectorXd& f, const Eigen::VectorXcd& z,
                              const Eigen::VectorXd& sigma, double k, std::string source) {
  if (z.size() != f.size() || (sigma.size() && sigma.size() != f.size()))
    throw std::invalid_argument("band_from_sigma: f, Z and sigma differ in length");
  ImpedanceBand b;
  b.f_hz = f;
  b.coverage_factor = k;
  b.source = std::move(source);
  b.abs_ohm = z.cwiseAbs();
  b.phase_rad.resize(f.size());
  b.abs_sigma_ohm = Eigen::VectorXd::Zero(f.size());
  b.phase_sigma_rad = Eigen::VectorXd::Zero(f.size());
  for (Eigen::Index i = 0; i < f.size(); ++i) {
    b.phase_rad[i] = std::arg(z[i]);
    if (sigma.size()) {
      b.abs_sigma_ohm[i] = sigma[i] / std::sqrt(2.0);
      b.phase_sigma_rad[i] = sigma[i] / (std::sqrt(2.0) * std::abs(z[i]));
    }
  }
  return b;
}

ImpedanceBand band_from_replicates(const Eigen::VectorXd& f, const Eigen::VectorXcd& z,
                                   const std::vector<Eigen::VectorXcd>& reps, std::size_t shots,
                                   double k, std::string source) {
  if (reps.size() < 2)
    throw std::invalid_argument("band_from_replicates: need at least 2 replicates");
  for (const auto& r : reps)
    if (r.size() != f.size())
      throw std::invalid_argument("band_from_replicates: a replicate has another grid");
  ImpedanceBand b = band_from_sigma(f, z, Eigen::VectorXd(), k, std::move(source));
  const double n = double(reps.size());
  const double inflate = shots > 1 ? std::sqrt(double(shots) / double(shots - 1)) : 1.0;
  for (Eigen::Index i = 0; i < f.size(); ++i) {
    double ml = 0, mp = 0;
    for (const auto& r : reps) {
      ml += std::log(std::abs(r[i]));
      mp += std::arg(r[i] / z[i]);
    }
    ml /= n;
    mp /= n;
    double vl = 0, vp = 0;
    for (const auto& r : reps) {
      vl += std::pow(std::log(std::abs(r[i])) - ml, 2);
      vp += std::pow(std::arg(r[i] / z[i]) - mp, 2);
    }
    b.abs_sigma_ohm[i] = b.abs_ohm[i] * std::sqrt(vl / (n - 1)) * inflate;
    b.phase_sigma_rad[i] = std::sqrt(vp / (n - 1)) * inflate;
  }
  return b;
}

void add_in_quadrature(ImpedanceBand& b, const Eigen::VectorXd& sigma) {
  if (sigma.size() != b.size())
    throw std::invalid_argument("add_in_quadrature: sigma has another length");
  for (Eigen::Index i = 0; i < b.size(); ++i) {
    const double sa = sigma[i] / std::sqrt(2.0), sp = sigma[i] / (std::sqrt(2.0) * b.abs_ohm[i]);
    b.abs_sigma_ohm[i] = std::hypot(b.abs_sigma_ohm[i], sa);
    b.phase_sigma_rad[i] = std::hypot(b.phase_sigma_rad[i], sp);
  }
}

std::vector<Eigen::VectorXcd> bootstrap_over_shots(
    std::size_t shots, std::size_t replicates, std::uint64_t seed,
    const std::function<Eigen::VectorXcd(const std::vector<std::size_t>&)>& replicate) {
  if (shots < 2) throw std::invalid_argument("bootstrap_over_shots: need at least 2 shots");
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<std::size_t> pick(0, shots - 1);
  std::vector<Eigen::VectorXcd> out;
  std::vector<std::size_t> idx(shots);
  for (std::size_t b = 0; b < replicates; ++b) {
    for (auto& i : idx) i = pick(rng);
    try {
      out.push_back(replicate(idx));
    } catch (const std::invalid_argument&) {
      // a degenerate resample (e.g. an estimator refusing it) carries no information
    }
  }
  return out;
}

}  // namespace piezo::dsp
