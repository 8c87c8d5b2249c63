#pragma once
// One Butterworth–Van Dyke (BVD) mode fitted to a measured impedance near its
// resonance: the motional branch R1–L1–C1 in parallel with C0 (IEEE Std
// 176-1987, "equivalent circuit" of an isolated resonance; EN 50324-2, the
// same four-element circuit), plus an optional known background admittance
// (the other modes' fitted branches). Start from a circle fit in the
// admittance plane, then Levenberg–Marquardt on Z(f) in ln R1, ln L1, ln C1,
// ln C0; covariance from the Jacobian. Pure functions; no search for modes here
// (dsp/mode_figures.hpp does that).
#include <Eigen/Core>
#include <complex>
#include <string>

#include "dsp/impedance_types.hpp"

namespace piezo::dsp {

struct BvdParams {
  double r1_ohm = kNaN, l1_h = kNaN, c1_f = kNaN, c0_f = kNaN;
  // Y(f) = j2πf·C0 + 1/(R1 + j2πf·L1 + 1/(j2πf·C1))
  std::complex<double> admittance(double f_hz) const;
  std::complex<double> motional_admittance(double f_hz) const;
};

// Circle x² + y² + D x + E y + F = 0 fitted algebraically (Kåsa) to points of
// the admittance plane. The motional admittance of a BVD branch is a circle of
// diameter 1/R1 through the origin; C0 shifts it by j·ωC0 (nearly constant
// over a resonance), so centre = 1/(2R1) + j·ωs·C0.
struct AdmittanceCircle {
  std::complex<double> centre;
  double radius = kNaN;
  double rms_distance = kNaN;  // rms of |y − centre| − radius
};
AdmittanceCircle fit_admittance_circle(const Eigen::VectorXcd& y);

// Start values from the circle of the points `first..last` (inclusive) of y
// (the measured admittance minus any background): R1 = 1/(2r), C0 = Im(centre)/ωs;
// each point's reactance X = R1·tan(φ), φ = −½·arg(y − centre) (the motional
// admittance is (1 + e^{−j2φ})/(2R1) with tan φ = X/R1); L1 and 1/C1 by linear
// least squares on X = ωL1 − 1/(ωC1). Throws std::invalid_argument on fewer
// than 3 points.
BvdParams bvd_start_from_circle(const Eigen::VectorXd& f_hz, const Eigen::VectorXcd& y,
                                Eigen::Index first, Eigen::Index last);

struct BvdFitOptions {
  int max_iterations = 200;
  double step_tolerance = 1e-13;  // on the ln-parameter step, converged below
};

struct BvdFit {
  BvdParams p;
  BvdParams sigma;                                           // 1σ of each parameter
  Eigen::Matrix4d cov_ln = Eigen::Matrix4d::Constant(kNaN);  // of (ln R1, ln L1, ln C1, ln C0)
  bool weighted = false;           // per-point σ of Z used (else residual-scaled)
  double chi2_per_dof = kNaN;      // with weights: Σ|r/σ|²/(2n − 4); else NaN
  double rms_rel_residual = kNaN;  // rms |Z_fit − Z|/|Z|
  std::size_t points = 0;
  int iterations = 0;
  bool converged = false;
  std::string message;  // why not, when !converged
};

// Fits p to z over the points first..last. z_sigma: sqrt(E|δZ|²) per point
// (same size as f, or empty: each point weighted by 1/|Z|, i.e. a relative fit,
// and the covariance scaled by the residual). y_background: admittance added to
// the BVD's (same size as f, or empty).
BvdFit fit_bvd(const Eigen::VectorXd& f_hz, const Eigen::VectorXcd& z,
               const Eigen::VectorXd& z_sigma, const Eigen::VectorXcd& y_background,
               Eigen::Index first, Eigen::Index last, const BvdParams& start,
               const BvdFitOptions& opt = {});

}  // namespace piezo::dsp
