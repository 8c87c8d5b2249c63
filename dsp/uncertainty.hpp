#pragma once
// Per-frequency uncertainty band of an impedance estimate, for |Z| and phase:
//   |Z| ± k·σ_|Z|,   arg Z ± k·σ_φ,
// from one of two sources:
//   * bootstrap over shots: the estimate (calibration included) repeated on
//     shots resampled with replacement (Efron & Tibshirani 1993, ch. 6); σ is
//     the spread of the replicates — every random effect that varies from shot
//     to shot is in it, nothing else is assumed;
//   * noise propagation: a per-point σ = sqrt(E|δZ|²) (ImpedanceResult::
//     z_sigma_ohm: Prony's parametric bootstrap, the FFT ratio's first-order
//     noise propagation, the coherence of the cross spectra), taken as
//     circular: σ_|Z| = σ/√2, σ_φ = σ/(√2·|Z|).
// Independent contributions (the estimate and the fixture standards) add in
// quadrature. k = 1.96 gives a 95 % band for Gaussian errors.
#include <Eigen/Core>
#include <complex>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace piezo::dsp {

struct ImpedanceBand {
  Eigen::VectorXd f_hz;
  Eigen::VectorXd abs_ohm, abs_sigma_ohm;      // |Z| and its standard uncertainty
  Eigen::VectorXd phase_rad, phase_sigma_rad;  // arg Z and its standard uncertainty
  double coverage_factor = 1.96;               // k: the band is value ± k·σ
  std::string source;                          // how σ was obtained

  Eigen::Index size() const { return f_hz.size(); }
  // True when z lies inside the band at point k (|Z| and phase both).
  bool covers(Eigen::Index k, std::complex<double> z) const;
};

// From a circular per-point σ (may be empty: zero band).
ImpedanceBand band_from_sigma(const Eigen::VectorXd& f_hz, const Eigen::VectorXcd& z,
                              const Eigen::VectorXd& sigma, double coverage_factor = 1.96,
                              std::string source = "noise propagation");

// From replicate estimates on the same grid: σ_|Z| = |Z|·std(ln|Z_b|), σ_φ = std(arg(Z_b/Z)),
// scaled by √(n/(n−1)) for the n shots resampled (the bootstrap of a mean of n
// underestimates its variance by (n−1)/n). Needs >= 2 replicates.
ImpedanceBand band_from_replicates(const Eigen::VectorXd& f_hz, const Eigen::VectorXcd& z,
                                   const std::vector<Eigen::VectorXcd>& replicates,
                                   std::size_t shots_resampled, double coverage_factor = 1.96,
                                   std::string source = "bootstrap over shots");

// Adds an independent circular σ (e.g. of the fixture standards) in quadrature.
void add_in_quadrature(ImpedanceBand& band, const Eigen::VectorXd& sigma);

// Bootstrap over shots: `replicate(indices)` estimates Z from the shots with
// those indices (drawn with replacement from 0..shots−1, same grid every
// time); replicates that throw std::invalid_argument are skipped.
std::vector<Eigen::VectorXcd> bootstrap_over_shots(
    std::size_t shots, std::size_t replicates, std::uint64_t seed,
    const std::function<Eigen::VectorXcd(const std::vector<std::size_t>&)>& replicate);

}  // namespace piezo::dsp
