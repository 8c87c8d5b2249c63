#pragma once
// Averaged auto/cross spectra over segments (Welch: window, overlap) of one or
// several records (seed eqs 157-161), the transfer T = V2/V1 of the divider and
// Z = R1·T/(1 − T). The two measured channels v1, v2 carry independent noise, so
// the spectra are formed on them (not on the current, whose noise is that of
// v2), with the estimators
//   H1 = G12/G11 (unbiased by output noise), H2 = G22/G21 (unbiased by input
//   noise), and the seed's eq. 161, the geometric mean |H1·H2|^½·e^{j∠H1}.
// Eq. 161 as printed, √(G_UP/G_PP · G_PU/G_UU), equals √γ² (its second factor is
// inverted: G_UP·G_PU = |G_UP|²); the geometric mean is what it is meant to be.
#include <Eigen/Core>
#include <span>

#include "dsp/divider.hpp"
#include "dsp/features.hpp"
#include "dsp/impedance_types.hpp"
#include "dsp/windows.hpp"

namespace piezo::dsp {

enum class SpectralEstimator { H1, H2, Eq161 };

struct CrossSpectraOptions {
  std::size_t segment = 0;  // samples per segment; 0: the shortest record
  double overlap = 0.5;     // fraction of a segment, [0, 0.95]
  Window window{WindowKind::Hann, 0.5};
  DividerPrep prep;         // applied to every record (prep.max_samples per record)
  SpectralEstimator estimator = SpectralEstimator::Eq161;
  bool difference = true;  // first difference of both channels (see FftRatioOptions)
  double fmin_hz = 0.0, fmax_hz = 0.0;  // bins kept; fmax 0: Nyquist
  FeatureOptions features;
};

struct CrossSpectra {
  Eigen::VectorXd f_hz;
  Eigen::VectorXd g11, g22;   // averaged auto spectra of v1, v2 (eqs 157-158)
  Eigen::VectorXcd g12;       // averaged cross spectrum conj(V1)·V2 (eqs 159-160)
  Eigen::VectorXcd h1, h2, h161;  // T = V2/V1 by the three estimators
  Eigen::VectorXd coherence;  // γ² = |G12|²/(G11·G22)
  std::size_t segments = 0;
  double r1_ohm = 0;
};

CrossSpectra cross_spectra(std::span<const DividerRecord> records, const CrossSpectraOptions& opt = {});

// Z = R1·T/(1 − T) with T from opt.estimator; per-point σ from the coherence
// (Bendat & Piersol: ε = √(1−γ²)/(|γ|·√(2·n_d)) on |T| and on ∠T).
ImpedanceResult impedance_xspec(std::span<const DividerRecord> records,
                                const CrossSpectraOptions& opt = {});

}  // namespace piezo::dsp
