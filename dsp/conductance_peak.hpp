#pragma once
// The motional conductance peak of one mode on a grid: series resonance fs at
// the conductance maximum and the half-power (−3 dB) frequencies f1, f2, so
// that Qm = fs/(f2 − f1) (EN 50324-2, "mechanical quality factor" from the
// resonance bandwidth; IEEE Std 176-1987 defines fs as the frequency of maximum
// motional conductance). Sub-grid values come from the resonance form itself:
// for a series R–L–C branch G = R/(R² + X²) and, with u = ω²,
//   u/G = R·u + (L·u − 1/C)²/R,
// a quadratic in u. Through any 3 grid points it is exact for a BVD branch, so
// the peak and both crossings are exact on noise-free BVD data at any grid step
// (a parabola in f through 3 points is not: Q = 150 with 3 points per bandwidth
// moves it by percents).
#include <Eigen/Core>
#include <string>

#include "dsp/impedance_types.hpp"

namespace piezo::dsp {

struct ConductancePeak {
  bool ok = false;
  std::string message;  // why not, when !ok
  double fs_hz = kNaN;  // maximum of G
  double g_max_s = kNaN;
  double f1_hz = kNaN, f2_hz = kNaN;  // G = G_max/2 below and above fs
  double qm = kNaN;                   // fs/(f2 − f1)
  double qm_sigma = kNaN;             // first order from g_sigma (NaN without it)
};

// g: conductance per grid point (the caller removes other modes' conductance),
// g_sigma: its 1σ per point or empty. The peak is the largest g in [lo, hi];
// the crossings are searched inside [lo, hi] too.
ConductancePeak conductance_peak(const Eigen::VectorXd& f_hz, const Eigen::VectorXd& g,
                                 const Eigen::VectorXd& g_sigma, Eigen::Index lo, Eigen::Index hi);

}  // namespace piezo::dsp
