#pragma once
// `piezobench model charge`: the seed's §5.1 simulation study on our FE tube,
// as the seed ran it (Figs 24–29). The tube's port model (24 short-circuit
// modes + the residual mode, as the simulated bench keeps) is driven by the
// analytic voltage v(t) = 500·e^{−0.001 t} V from t = 0 (eq. 111) and its
// electrode CHARGE is recorded at 10 MS/s for 5 ms (model/transient.hpp).
// §5.1.1: Rayleigh β = 0, noise-free; §5.1.2: β = 1e-7 s and white noise of
// std = level·std(clean charge) on the charge (the seed's σn/σs; the drive is
// analytic, so noise-free). Then, against the port model's harmonic |Z| (the
// stepped-harmonic truth, which no estimator sees):
// - Prony-SS on the charge (dsp/prony_charge.hpp, eqs 111–116) from the first
//   N samples, with the seed's order rule (largest singular-value drop among
//   the first 100, its 500 × 500 Hankel) and with the house noise-floor rule;
// - the direct FFT ratio V_k/(j2πf_k·Q_k) of the first N samples and of the
//   whole record (Figs 25, 26);
// - the averaged cross spectra of `records` independent noisy records, H1 =
//   G_vq/G_vv (Fig 26; H1 because the drive is noise-free, so H1 is unbiased).
// Scored by dsp/reference_comparison.hpp (|Z| error away from the peaks, feature
// errors). Plots: the signals (Fig 24), |Z| and its error (Figs 25/26/28/29),
// the singular values (Fig 27).
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "jobs/model_job.hpp"

namespace piezo::jobs {

struct ChargeStudyRequest {
  ModelRequest model;                   // the tube (default: the published APC850 tube)
  double noise = 0.0;                   // σn/σs on the charge; 0: §5.1.1
  std::optional<double> beta_s;         // Rayleigh β; default 0 without noise, 1e-7 s with (the seed's)
  std::vector<std::size_t> samples{1000, 3000};  // Prony and FFT on the first N samples
  std::size_t hankel = 500;             // the seed's ξ = η for its order rule (capped at N/2)
  std::size_t records = 20;             // the cross spectra's records (with noise only)
  std::uint64_t seed = 1;               // the noise draw
  int modes = 24;                       // short-circuit modes of the port model
  std::string plot_dir;                 // non-empty: write the figures there
  std::string plot_format = "svg";      // svg | png
  std::string csv;                      // non-empty: |Z| of the truth and every estimate on the 200 Hz grid
};

// Throws InputError for a bad request (noise < 0, N outside 100..50000, a
// plot format other than svg/png, an unwritable file), std::invalid_argument
// for an unknown material.
nlohmann::json run_charge_study(const ChargeStudyRequest& request);

}  // namespace piezo::jobs
