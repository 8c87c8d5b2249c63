#pragma once
// The seed's own Laplace-domain impedance estimator (§4.2, eqs 111–116): the
// transducer is driven by a voltage of analytic form and its electrode CHARGE
// is decomposed, instead of the divider's v1/v2 (dsp/prony_impedance.hpp).
//   v(t) = γv·e^{λv t}, t >= 0                     (eq. 111) → V(s) = γv/(s − λv)  (eq. 113)
//   q(t_k) = Σ_n γ_n e^{λ_n t_k}  by Prony-SS       (eq. 112) → Q(s) = Σ γ_n/(s − λ_n) (eq. 114)
//   I(s) = s·Q(s)                                   (eq. 115)
//   Z(s) = V(s)/I(s),  s = jω                       (eq. 116)
// Eq. 115 is L{dq/dt} = s·Q(s) − q(0−) with the charge at rest before the drive
// (q(0−) = 0, the seed's "if the initial charge c(0) is equal to 0"). A drive
// that steps at t = 0 charges the clamped capacitance at once, so the samples
// start at q(0+) = C_e·γv ≠ 0: that jump is the Dirac current of the step, and
// s·Q(s) with Q the transform of the fitted sum from t = 0 carries it. Using
// q(0+) in place of q(0−) would drop the clamped capacitance from I.
//
// The drive is either given analytically (one input pole, the seed's §5.1) or
// recorded and decomposed by Prony-SS as well (its own fit: V(s) = Σ γ/(s − λ)).
#include <Eigen/Core>
#include <complex>
#include <optional>

#include "dsp/features.hpp"
#include "dsp/impedance_types.hpp"
#include "dsp/prony_ss.hpp"

namespace piezo::dsp {

// v(t) = amplitude·e^{pole·t} for t >= 0, 0 before (eq. 111: γv, λv).
struct ExponentialDrive {
  double amplitude_v = 0.0;
  double pole_per_s = 0.0;  // λv (real; the seed's −1e-3 1/s)
  std::complex<double> laplace(std::complex<double> s) const;  // eq. 113
};

struct PronyCharge {
  PronyFit fit;                           // the charge q(t) from t = 0 (eqs 112, 114)
  std::optional<ExponentialDrive> drive;  // analytic drive, or
  std::optional<PronyFit> drive_fit;      // the recorded drive's own decomposition
  std::complex<double> voltage(std::complex<double> s) const;  // V(s), eq. 113 (or 114 for v)
  std::complex<double> charge(std::complex<double> s) const;   // Q(s), eq. 114
  std::complex<double> current(std::complex<double> s) const;  // I(s) = s·Q(s), eq. 115
  std::complex<double> z(double f_hz) const;                    // V/I at s = j2πf, eq. 116
};

// q: charge samples, sample 0 at t = 0 (the drive's onset). Throws
// std::invalid_argument like prony_ss, and for a non-finite drive or a zero amplitude.
PronyCharge fit_prony_charge(const Eigen::Ref<const Eigen::VectorXd>& q, double sample_rate_hz,
                             const ExponentialDrive& drive, const PronyOptions& opt = {});

// The recorded drive v (same length and instants as q) decomposed on its own
// with drive_opt (one exponential for the seed's drive: give order 1, or let
// the automatic rule find it).
PronyCharge fit_prony_charge(const Eigen::Ref<const Eigen::VectorXd>& q,
                             const Eigen::Ref<const Eigen::VectorXd>& v, double sample_rate_hz,
                             const PronyOptions& opt = {}, const PronyOptions& drive_opt = {});

// Z on the grid f_hz (ascending, > 0), its |Z| extrema (located on a grid of
// feature_step_hz, 0: a quarter of the grid's step, refined by golden section,
// dsp/features.hpp), the charge fit's order, singular values and poles.
ImpedanceResult impedance_from_charge(const PronyCharge& m, const Eigen::VectorXd& f_hz,
                                      const FeatureOptions& features = {},
                                      double feature_step_hz = 0.0);

}  // namespace piezo::dsp
