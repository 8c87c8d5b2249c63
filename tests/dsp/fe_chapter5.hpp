#pragma once
// Seed chapter 5.1.2 on OUR FE model (test support for the chapter-5 study):
// the published tube (shared/reference/published-tube-results.json: Di 16 mm,
// Do 19 mm, L 20 mm, APC850 Table 2, free-free) reduced to its electrical port
// by the modal solver (24 short-circuit modes + residual mode, as the simulated
// bench keeps), Rayleigh α = 0, β = 1e-7 s, in the divider of the seed's lab
// circuit (R1 = 3140 Ω), driven by v1 = 500·e^{−0.001 t} V from t = 0 for 5 ms
// at 10 MS/s (the seed's §5.1.1 input).
//
// The clean records are the FE transient of model/transient.hpp (the modal
// state space discretised exactly for piecewise-linear input, at rest at t = 0:
// the drive is a step at sample 0). The same response is also given as an
// exact pole–residue sum (eigen-decomposition of the same modal circuit, built
// here independently of model/transient.cpp) for the Cramér–Rao bounds; the
// two agree to round-off (tested). Noise as the seed defines it: white, per
// channel, std = level·std(clean channel over the 5 ms record from t = 0).
#include <complex>
#include <cstdint>
#include <utility>
#include <vector>

#include "bvd_model.hpp"
#include "crb.hpp"
#include "impedance_study.hpp"
#include "model/port_model.hpp"

namespace piezo::fe5 {

struct FeChapter5 {
  model::ModalPortModel port;
  model::RayleighDamping damping{0.0, 1e-7};
  double r1_ohm = 3140.0, sample_rate_hz = 1e7;
  double amplitude_v = 500.0, decay_per_s = 1e-3;
  std::size_t record = 50000;                 // 5 ms
  std::vector<double> v1, v2;                 // clean FE transient from t = 0 (sample 0 is t = 0)
  bvd::DividerResponse exact;                 // v1, v2, i as pole–residue sums (same response)
  std::complex<double> z(double f_hz) const;  // Z = 1/(jω·Q/V) of the port model
};

// Built once per process (FE assembly, modal solve, one transient run).
const FeChapter5& chapter5();

// The study input: `records` independent noisy copies of the clean records
// (record 0 feeds Prony and the FFT; all of them the cross spectra), true Z and
// the true |Z| extrema in 1–120 kHz. The input's z_true refers to `fe`, which
// must outlive it (chapter5() does).
study::StudyInput study_input(const FeChapter5& fe, double level, std::uint64_t seed,
                              std::size_t records);

// Channel noise std of the seed's definition at `level` (v1, v2).
std::pair<double, double> noise_std(const FeChapter5& fe, double level);

// The divider response as the CRB's model (crb.hpp): real poles and one Im > 0
// member per pair, channels {v1, v2} with their residues and noise std.
struct CrbModel {
  std::vector<std::complex<double>> poles;
  std::vector<crb::Channel> channels;
};
CrbModel crb_model(const bvd::DividerResponse& r, double sigma_v1, double sigma_v2);

// Flags (for crb's `known`) every pole except the real poles up to f_max_hz
// (drive, divider node) and the `pairs` oscillating poles up to f_max_hz with
// the largest v2 residues: the reduced model class an order-(2·pairs + 2) fit
// estimates. The CRB with the rest known is a lower bound of the full one.
std::vector<bool> known_except_dominant(const CrbModel& m, double f_max_hz, std::size_t pairs);

// CRBs on the chapter-5 data at noise `level` from the first n samples. Full:
// every pole of the FE response free. Reduced: the order-8 model class (drive
// and divider-node poles, the three strongest pairs below 130 kHz), the rest
// known — a lower bound of the full one, and the bound that applies to a fit of
// that reduced model (which the full-model bound need not, see README).
enum class CrbClass { Full, Reduced };

// Relative 1σ of each true feature of `in` (resonances, anti-resonances).
struct FeatureBounds {
  std::vector<double> res_rel, anti_rel;
};
FeatureBounds feature_crb(const FeChapter5& fe, const study::StudyInput& in, double level,
                          std::size_t n, CrbClass cls);

// 1σ of 20·log10|Z| (dB) at each f.
std::vector<double> db_crb(const FeChapter5& fe, double level, std::size_t n,
                           const std::vector<double>& f_hz, CrbClass cls);

}  // namespace piezo::fe5
