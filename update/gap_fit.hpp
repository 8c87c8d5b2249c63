#pragma once
// Weighted fit of a GapModel to a measured impedance. The misfit is the
// complex log residual ln Z_meas − ln Z_model (real part: log-magnitude in
// nepers, imaginary part: phase in rad), each divided by the measurement's
// own standard error at that frequency (from the repeated shots), combined in
// quadrature with a relative model floor. χ² ≈ N for a model that is right to
// within the noise. Levenberg–Marquardt with box bounds, central-difference
// Jacobian on the linearised model, re-linearised when the material moves.
#include <Eigen/Core>
#include <complex>
#include <string>
#include <vector>

#include "update/gap_model.hpp"

namespace piezo::update {

struct GapData {
  std::vector<double> f_hz;
  std::vector<std::complex<double>> z_ohm;
  std::vector<double> sigma_log_mag, sigma_phase;  // total standard error per point (noise ⊕ floor)
  std::string description;                        // e.g. "fit capture: 16 exp_decay shots"
  std::size_t size() const { return f_hz.size(); }
  void validate(const char* who) const;  // throws std::invalid_argument
};

struct GapFit {
  std::vector<double> x;        // all parameters (fixed ones at their start)
  std::vector<bool> free;
  std::vector<double> sigma_x;  // standard errors (free only; 0 for fixed), scaled by max(1, χ²/dof)
  Eigen::MatrixXd covariance;   // of the free parameters, same scaling (order of `free`)
  double chi2 = 0;
  int n = 0;                    // residuals (2 per frequency)
  int dof = 0;                  // n − free parameters
  int iterations = 0;
  bool converged = false;
  std::string message;
};

// Weighted residual vector (2 per frequency).
std::vector<double> gap_residuals(const GapModel& m, const GapData& d, const std::vector<double>& x);
double gap_chi2(const GapModel& m, const GapData& d, const std::vector<double>& x);

struct GapFitOptions {
  int max_iterations = 200;
  double chi2_tolerance = 1e-7;  // relative
  int max_relinearisations = 12;  // a 3 % end mass needs ~10 (GapDiagnosisExact.EndMass…)
  double relinearise_beyond = 0.3;  // x units (0.3 % of a material parameter)
};

GapFit fit_gap(GapModel& m, const GapData& d, const std::vector<double>& x0, const std::vector<bool>& free,
               const GapFitOptions& opt = {});

// χ² of `d` (data the fit never saw) under the fitted model, with the
// residuals' covariance widened by the fit's own parameter uncertainty
// (I + J C Jᵀ, full, not per point): a held-out curve measured more precisely
// than the fit data must not call the fit's statistical uncertainty a gap.
double predictive_chi2(const GapModel& m, const GapData& d, const GapFit& fit);

// Weighted Jacobian columns ∂r/∂x_j at x (central differences), for the alias analysis.
std::vector<std::vector<double>> gap_jacobian(const GapModel& m, const GapData& d, const std::vector<double>& x,
                                              const std::vector<int>& columns);

}  // namespace piezo::update
