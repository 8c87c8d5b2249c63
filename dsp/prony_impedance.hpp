#pragma once
#include <optional>
// The proposed Laplace-domain impedance estimator (seed §4.2, §4.3.2): v1, v2 and
// the current i = (v1 − v2)/R1 from t = 0 are decomposed together by the
// multi-signal Prony-SS method (one set of global poles, so the output holds the
// input's poles), and
//     Z(s) = V2(s)/I(s) = R1·V2(s)/(V1(s) − V2(s))          (eqs 113-116, 170)
// is evaluated from the pole–residue forms at s = jω on any grid: no leakage,
// any resolution. The drive step at t = 0 is part of the one-sided transform:
// the fit starts at the first sample of the excitation, so nothing is lost.
#include <array>
#include <complex>
#include <cstdint>

#include "dsp/divider.hpp"
#include "dsp/features.hpp"
#include "dsp/impedance_types.hpp"
#include "dsp/prony_ss.hpp"

namespace piezo::dsp {

struct PronyImpedanceOptions {
  PronyOptions prony;
  DividerPrep prep;  // prep.max_samples: the samples from t = 0 decomposed (0: all)
  FeatureOptions features;
  double feature_step_hz = 0.0;  // search grid of the features; 0: grid step / 4
  // Parametric bootstrap for the uncertainties of the features and of Z per point
  // (z_sigma_ohm): refits with white noise of the fit's residual RMS added to the
  // model on v1 and v2, at the chosen order. 0: no σ.
  std::size_t bootstrap = 0;
  std::uint64_t bootstrap_seed = 7;
  // How the drive reaches its first sample. false: it steps at t = 0 (the
  // seed's transient). true: it leaves its idle level at the last pretrigger
  // sample and ramps linearly to the first one (an AWG joining its samples
  // linearly, as the simulated bench's does): the [−Δt, 0) segment of every
  // signal, linear from rest to its first sample, is added to the transforms.
  // Leaving it out of a ramped drive reads as a channel-2 lead of Δt/2
  // (2° at 110 kHz, 10 MS/s).
  bool ramp_onset = false;
  // The first `direct_samples` samples from t = 0 enter the transforms as
  // recorded: the poles and residues are fitted from sample direct_samples on
  // (PronyOptions::skip_samples; the residues still refer to t = 0), and what
  // the pole model leaves of the signals before that sample — the fast
  // transient of modes above the band, which the decimated Hankel matrices
  // cannot see — is integrated numerically (linear between samples) and added
  // to V1, V2, I. 0: the pole model from t = 0 (the seed's estimator).
  // kDirectFilterLength: 10·D, the length of the decimation filter (D from
  // PronyOptions), i.e. the span before the first decimated sample.
  static constexpr std::size_t kDirectFilterLength = static_cast<std::size_t>(-1);
  std::size_t direct_samples = 0;
};

struct PronyImpedance {
  PronyFit fit;  // signals: 0 = v1, 1 = v2, 2 = i
  double r1_ohm = 0.0;
  // The ramp onto the first samples (PronyImpedanceOptions::ramp_onset):
  // onset_dt_s = Δt (0: none), onset_v = the signals' values at t = 0.
  double onset_dt_s = 0.0;
  std::array<double, 3> onset_v{};
  // PronyImpedanceOptions::direct_samples: the signals minus the pole model on
  // the first samples (rows k = 0.., t = kΔt; empty: none), Δt = fit.dt.
  Eigen::MatrixXd direct_residual;
  // Laplace transform of signal k (0 = v1, 1 = v2, 2 = i) from the start of the drive.
  std::complex<double> transform(Eigen::Index k, std::complex<double> s) const;
  std::complex<double> z(double f_hz) const;  // eq. 116 at s = j2πf

  // The zero (resonance) or pole (anti-resonance) of Z(s) nearest to the |Z|
  // extremum at f_hz, by Newton's method on Z(s) (zeros) or on 1/Z(s) (poles);
  // returns s* (NaN if it does not converge).
  std::complex<double> zero_or_pole(double f_hz, bool resonance) const;
};

// Replaces each extremum of `f` by the natural frequency of the zero / pole of
// Z(s) next to it (see Feature); keeps the extremum in extremum_hz.
void refine_features_to_modal(const PronyImpedance& m, ImpedanceFeatures& f);

PronyImpedance fit_prony_impedance(const DividerRecord& rec, const PronyImpedanceOptions& opt = {});

// The same fit at several orders (0: automatic; opt.prony.order is ignored)
// from one Hankel SVD (dsp::prony_ss_orders): one entry per order, empty
// where the data cannot carry that order. Throws like fit_prony_impedance for
// a record that cannot be fitted at all.
std::vector<std::optional<PronyImpedance>> fit_prony_impedance_orders(
    const DividerRecord& rec, const PronyImpedanceOptions& opt,
    const std::vector<std::size_t>& orders);

// Sets m.direct_residual to the first n rows of y (v1, v2, i from t = 0) minus
// m's pole model (n = 0: none).
void attach_direct_residual(PronyImpedance& m, const Eigen::MatrixXd& y, Eigen::Index n);

// Z on the grid f_hz (ascending, >= 0), features, order and singular values.
ImpedanceResult impedance_prony(const DividerRecord& rec, const Eigen::VectorXd& f_hz,
                                const PronyImpedanceOptions& opt = {});

// The summary (order, normalised singular values, poles) of a fit.
PronySummary summarize(const PronyFit& fit);

}  // namespace piezo::dsp
