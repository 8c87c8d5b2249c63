#pragma once
// Measured calibration standards (open, short, load) and their smooth models.
//
// A standard measured through the divider bench is a low-order, smooth
// function of frequency over the audio/ultrasonic band: after the error box
// of the fixture (lead resistance, fixture capacitance, DAQ input, R1 error,
// channel gain and skew) the open's admittance is G + jωC + O(ω²τ²), the
// short's impedance R + jωL + …, the load's nearly its resistance. Each is
// fitted by weighted least squares with a polynomial in jω with REAL
// coefficients (the response of a real-valued system: X(−jω) = X(jω)*),
//     X(jω) = Σ_k c_k·(jω/ω_s)^k,   X = Y for the open, Z for short and load,
// which averages the noise of every frequency bin into a few coefficients and
// evaluates the standard at any frequency of any estimator's grid. The fit's
// residual says whether the fixture is as smooth as assumed.
#include <Eigen/Core>
#include <complex>
#include <string>

namespace piezo::dsp {

// One standard as the divider formula with nominal R1 gives it, on a grid.
struct MeasuredStandard {
  Eigen::VectorXd f_hz;
  Eigen::VectorXcd z_ohm;
  Eigen::VectorXd z_sigma_ohm;  // per point sqrt(E|δZ|²); empty: equal weights (relative)
};

struct StandardModel {
  bool admittance = false;   // the polynomial is Y (open) or Z (short, load)
  double omega_scale = 1.0;  // ω_s, rad/s
  double fmin_hz = 0,
         fmax_hz = 0;   // fitted range (evaluation above fmax throws; below fmin it extends to DC)
  Eigen::VectorXd c;    // real coefficients c_0..c_deg
  Eigen::MatrixXd cov;  // their covariance (from the weights, scaled by the reduced χ² when > 1)
  double residual_rel_rms = 0;  // rms of |X_meas − X_fit|/|X_fit| over the points
  double chi2_reduced = 0;      // Σ(|r|/σ)²/(2n − p); ~1 when the model fits to the noise
  std::size_t points = 0;

  std::complex<double> impedance(double f_hz) const;
  std::complex<double> admittance_at(double f_hz) const { return 1.0 / impedance(f_hz); }
  // sqrt(E|δZ|²) of the model's Z at f from the coefficient covariance.
  double impedance_sigma(double f_hz) const;
};

// Weighted LS fit of a standard, `degree` ≤ 8 (≥ 1), over the points with f > 0.
// Throws std::invalid_argument naming the standard (`what`) for too few points,
// non-finite values or a degenerate fit.
StandardModel fit_standard(const MeasuredStandard& m, bool as_admittance, int degree,
                           const std::string& what);

}  // namespace piezo::dsp
