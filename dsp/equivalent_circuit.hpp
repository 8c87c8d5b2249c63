#pragma once
// A multi-mode equivalent circuit fitted to a complex impedance Z(f) (issue
// 34): the modified Butterworth–Van Dyke network of IEEE Std 176-1987 and
// EN 50324-2 extended to every mode in the band —
//
//   Z(f) = Rs + 1 / ( jωC0(1 − j·tanδ) + Σ_k 1/(R_k + jωL_k + 1/(jωC_k)) )
//
// one clamped capacitance C0 with its dielectric loss (a constant tan δ: the
// loss conductance ωC0·tanδ, i.e. R0 = 1/(ωC0·tanδ) at each frequency), an
// optional series resistance Rs (leads, electrodes), and one motional R-L-C
// branch per mode. All branches are fitted jointly, by weighted least squares
// on Re and Im of Z (the shared engine, numerics/levenberg_marquardt), in the logs
// of the elements. The number of branches is chosen by the Bayesian
// information criterion: a branch is added where the residual stands out and
// kept only if the criterion falls; a branch whose removal lowers it, or whose
// resonance leaves the data's band, is dropped — so close pairs are resolved
// and no mode appears where there are no data.
//
// The figures of each mode follow from the fitted network (IEEE 176 and
// EN 50324-2 definitions, each named), with σ from the fit's covariance
// inflated by its lack of fit (χ²/ν when above 1), propagated by finite
// differences.
#include <Eigen/Core>
#include <complex>
#include <string>
#include <utility>
#include <vector>

#include "dsp/impedance_types.hpp"

namespace piezo::dsp {

struct CircuitBranch {
  double r_ohm = kNaN, l_h = kNaN, c_f = kNaN;
  double fs_hz() const;  // 1/(2π√(LC))
  double qm() const;     // 2π·fs·L/R
};

struct EquivalentCircuit {
  double c0_f = kNaN;
  double tan_delta = 0;  // of C0
  double rs_ohm = 0;     // 0: no series resistance in the model
  std::vector<CircuitBranch> branches;  // ascending fs
  std::complex<double> admittance_without_rs(double f_hz) const;
  std::complex<double> impedance(double f_hz) const;
  // The same network without losses (R_k = 0, tanδ = 0, Rs = 0): its
  // susceptance, whose zeros are the parallel resonances fp (Foster).
  double lossless_susceptance(double f_hz) const;
};

struct Figure {
  double value = kNaN;
  double sigma = kNaN;  // 1σ, including the fit's lack of fit
};

struct CircuitModeFigures {
  // Motional branch (IEEE 176 "series" and "parallel" resonance of the
  // lossless network): fs = 1/(2π√(L_kC_k)); fp = the zero of the lossless
  // susceptance between fs_k and fs_{k+1}. A weak branch lying between a
  // strong one's fs and fp (C_k below a tenth of the strong one's) would take
  // that zero: it is the strong mode's "guest", has no fp (NaN: its
  // background is inductive there), and the strong mode's fp is found with
  // its guests standing as their static capacitance.
  Figure fs_hz, fp_hz;
  // |Z| minimum and maximum of the fitted network (IEEE 176 fm, fn).
  Figure fm_hz, fn_hz;
  // Zero-phase frequencies near fm and fn (IEEE 176 fr, fa); NaN when the
  // mode's phase never reaches zero (low Q, strong background).
  Figure fr_hz, fa_hz;
  Figure k_eff_ieee176;    // √(1 − (fs/fp)²), IEEE 176 dynamic coupling
  Figure k_eff_en50324;    // √(1 − (fm/fn)²), EN 50324-2's form from the |Z| extrema
  Figure qm_branch;        // 2π·fs·L/R
  Figure qm_bandwidth;     // f_G/(f2 − f1), the network's conductance half-power points
  Figure r1_ohm, l1_h, c1_f;
  double window_lo_hz = kNaN, window_hi_hz = kNaN;  // the mode's share of the band
  double misfit_rel_rms = kNaN;  // √mean(|Z_fit − Z|²/|Z|²) in that window
  int points = 0;                // data points in the window
  // Whether the figures can be trusted (dsp/circuit_adequacy.hpp): "ok", or
  // "unreliable" with the reasons (misfit in the window, implausible values,
  // the two k_eff forms disagreeing, a Q the grid or the window cannot
  // resolve, a resonance outside the data). An unreliable figure never passes
  // a limit.
  std::string status = "ok";
  std::vector<std::string> reasons;
  // How σ was widened beyond the fit's covariance (residual correlation in the
  // window, the offset from the data's own conductance / resistance maximum).
  std::vector<std::string> sigma_notes;
};

struct CircuitFitOptions {
  int max_branches = 12;
  // Modes to seed the search with (fs, Q; from dsp/mode_figures or the
  // |Z| minima); empty: the conductance peaks of the data.
  std::vector<double> seed_fs_hz;
  // Try the series resistance Rs (kept if the criterion falls).
  bool try_series_resistance = true;
  // Fit |Z| only (ln|Z| residuals): for files whose phase cannot be trusted
  // (a passive part with Re Z < 0). Set automatically when most points have
  // Re Z < 0.
  bool magnitude_only = false;
  bool auto_magnitude_only = true;  // off for an estimate whose phase is defined (a capture's)
  int max_iterations = 200;
};

struct CircuitFit {
  EquivalentCircuit circuit;
  std::vector<CircuitModeFigures> modes;  // one per branch, ascending fs
  Figure c0_f, tan_delta, rs_ohm;
  Figure free_capacitance_f;  // C^T = C0 + Σ C_k: the network's capacitance as f → 0
  double chi2 = kNaN;         // Σ r² (weighted) or the residual sum of squares (relative)
  int points = 0, parameters = 0;
  double chi2_per_dof = kNaN;
  double bic = kNaN;
  bool weighted = false;       // per-point σ given
  bool magnitude_only = false;
  bool converged = false;
  double misfit_rel_rms = kNaN;        // of Z over the band
  double misfit_abs_rel_rms = kNaN;    // of |Z| over the band
  double misfit_admittance_abs_rel_rms = kNaN;  // of |Y| over the band
  std::vector<std::string> notes;      // order selection, dropped modes, assumptions
  // Adequacy (dsp/circuit_adequacy.hpp): "ok", or "inadequate" when the
  // network cannot describe the data (|Z| misfit above 10 %, not converged, C0
  // absorbed into a branch); the reasons say which.
  std::string status = "ok";
  std::vector<std::string> status_reasons;
  // The data's own noise from their point-to-point scatter (relative, per
  // component of Z, or of ln|Z| when magnitude only), and the fit's residual
  // RMS in units of it (1: the network explains the data to their noise).
  double noise_scatter_rel = kNaN;
  double residual_to_scatter = kNaN;
  double residual_lag1 = kNaN;  // lag-1 autocorrelation of the residual over the band
  // The data's conductance peaks with a clear prominence, and the mode each
  // became (−1: none; the notes say why).
  struct DataPeak {
    double f_hz = kNaN, prominence_s = kNaN;
    int mode = -1;
  };
  std::vector<DataPeak> data_peaks;
};

// f ascending, z the measured impedance, z_sigma per point sqrt(E|δZ|²) or
// empty (relative weights; the residual then sets the noise scale). Throws
// std::invalid_argument on sizes that differ, fewer than 8 points, a
// non-positive or non-ascending frequency, or a non-finite Z.
CircuitFit fit_equivalent_circuit(const Eigen::VectorXd& f_hz, const Eigen::VectorXcd& z,
                                  const Eigen::VectorXd& z_sigma, const CircuitFitOptions& opt = {});

// The per-mode figures by name in one fixed order (JSON keys, CSV columns, the σ propagation).
std::vector<std::pair<const char*, Figure*>> named_figures(CircuitModeFigures& m);
std::vector<std::pair<const char*, const Figure*>> named_figures(const CircuitModeFigures& m);

// Figures of branch k of a circuit (values only; fit_equivalent_circuit adds σ).
CircuitModeFigures circuit_mode_figures(const EquivalentCircuit& c, std::size_t k);

}  // namespace piezo::dsp
