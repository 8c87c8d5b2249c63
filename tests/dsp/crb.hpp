#pragma once
// Cramér–Rao bounds for the multi-channel damped-exponential model the Prony-SS
// fit uses (shared poles, free complex residues per channel, independent white
// Gaussian noise of std sigma[c] on channel c), sampled at k = 0..n−1:
//   y_c[k] = Σ_i r_ci e^{λ_i k/fs} (+ conjugates of the pairs).
// Bounds: the frequency of one pole, and a frequency feature of the divider
// impedance Z(s) = R1·V2(s)/(V1(s) − V2(s)) built from the same parameters
// (channel 0 = v1, channel 1 = v2; R1 cancels): a |Z| minimum (resonance) or
// maximum (anti-resonance), through the delta method (∂f*/∂θ by the
// implicit-function theorem on d ln|Z(jω)|/dω = 0).
#include <Eigen/Core>
#include <complex>
#include <vector>

namespace piezo::crb {

struct Channel {
  std::vector<std::complex<double>> residue;  // one per pole of `poles` (0 allowed)
  double sigma = 0;                           // noise std
};

// poles: real poles and one representative (Im > 0) per conjugate pair; the
// residues of a pair's conjugate are the conjugates. Returns the CRB standard
// deviation in Hz of Im(poles[index])/2π from samples k = 0..n−1 at fs.
// `known`: as for divider_feature_crb below.
double pole_frequency_crb_hz(const std::vector<std::complex<double>>& poles,
                             const std::vector<Channel>& channels, double fs, std::size_t n,
                             std::size_t index, const std::vector<bool>& known = {});

// The |Z| extremum of the divider impedance of the model (channels {v1, v2})
// next to f_start_hz, by Newton's method on d ln|Z(jω)|/dω (NaN: no convergence).
double divider_feature_hz(const std::vector<std::complex<double>>& poles,
                          const std::vector<Channel>& channels, double f_start_hz);

// ∂f*/∂θ of that extremum (Hz per parameter unit), θ in the layout: per pole
// (Re λ[, Im λ]) in pole order, then per pole per channel (Re r[, Im r]); real
// poles take one entry each, pairs two.
Eigen::VectorXd divider_feature_gradient(const std::vector<std::complex<double>>& poles,
                                         const std::vector<Channel>& channels, double f_hz);

struct FeatureCrb {
  double f_hz = 0;      // the feature of the exact model (|Z| extremum, Newton-refined)
  double sigma_hz = 0;  // CRB standard deviation
};

// The extremum next to `f_start_hz` and its CRB from samples k = 0..n−1 at fs.
// Poles flagged in `known` (one flag per pole, or empty: none) are treated as
// known, with their residues: the bound then holds for a smaller parameter set
// and is a lower bound of the full one (and the bound of a fit of the reduced
// model, as far as the data are that model: the flagged components contribute
// only a small bias then).
FeatureCrb divider_feature_crb(const std::vector<std::complex<double>>& poles,
                               const std::vector<Channel>& channels, double fs, std::size_t n,
                               double f_start_hz, const std::vector<bool>& known = {});

// The same for several features (the Fisher matrix is formed once).
std::vector<FeatureCrb> divider_feature_crb(const std::vector<std::complex<double>>& poles,
                                            const std::vector<Channel>& channels, double fs,
                                            std::size_t n, const std::vector<double>& f_start_hz,
                                            const std::vector<bool>& known = {});

// CRB standard deviation (dB) of 20·log10|Z(j2πf)| at each f of the same model.
std::vector<double> divider_db_crb(const std::vector<std::complex<double>>& poles,
                                   const std::vector<Channel>& channels, double fs, std::size_t n,
                                   const std::vector<double>& f_hz,
                                   const std::vector<bool>& known = {});

}  // namespace piezo::crb
