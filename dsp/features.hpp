#pragma once
// Impedance features: resonances (local minima of |Z|), anti-resonances (local
// maxima) with sub-grid refinement, and the low-frequency capacitance, each with
// a standard uncertainty propagated from the per-point uncertainty of Z.
#include <Eigen/Core>
#include <complex>
#include <functional>
#include <limits>

#include "dsp/impedance_types.hpp"

namespace piezo::dsp {

struct FeatureOptions {
  double fmin_hz = 0.0;                                          // search band
  double fmax_hz = std::numeric_limits<double>::infinity();
  // An extremum counts when |Z| rises (falls) by at least this much on both
  // sides before a lower minimum (higher maximum) is met, within ±search_rel·f.
  double min_prominence_db = 0.3;
  double search_rel = 0.15;
  // Grid refinement: weighted quadratic fit of 20·log10|Z| over ±fit_points.
  int fit_points = 1;
  // Capacitance band; 0: auto = [first grid point > 0, cap_rel_hi × lowest resonance]
  // (or × fmax without resonance). Fit: Im(1/Z) = ω·(C + D·ω²).
  double cap_f_lo_hz = 0.0, cap_f_hi_hz = 0.0;
  double cap_rel_hi = 0.3;
};

// From an impedance on a grid; z_sigma (same size, or empty) is sqrt(E|δZ|²) per
// point. Without z_sigma, uncertainties come from the fit residuals.
ImpedanceFeatures find_features(const Eigen::VectorXd& f_hz, const Eigen::VectorXcd& z,
                                const Eigen::VectorXd& z_sigma, const FeatureOptions& opt = {});

// From an impedance known at any frequency (the Prony pole–residue model): the
// extrema are located on a grid of `step_hz` and refined by golden-section search
// to 1e-10 relative; uncertainties are left NaN (see impedance_prony's bootstrap).
ImpedanceFeatures find_features(const std::function<std::complex<double>(double)>& z,
                                double fmin_hz, double fmax_hz, double step_hz,
                                const FeatureOptions& opt = {});

}  // namespace piezo::dsp
