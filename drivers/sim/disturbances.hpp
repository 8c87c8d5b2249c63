#pragma once
// A real bench's slow disturbances for the simulated bench (issue 33 item 4):
// what real captures have on top of white noise. DC offset per channel, mains
// hum with harmonics and pink (1/f) noise are added to the DAQ's input like
// its other imperfections (sim_bench.cpp); drift and a step of the
// transducer's constants between shots change the device itself (the physics
// rebuilds its port model, BenchPhysics::set_constant_factors); trigger
// jitter moves the DAQ's sampling instants against the excitation. Everything
// defaults to off, and off changes nothing — not a sample, not an RNG draw
// (the disturbances draw from their own generator, seeded from the bench's
// seed). Model and option string: acquisition/README.md.
#include <cstddef>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "drivers/sim/bench_physics.hpp"

namespace piezo::drivers::sim {

struct Disturbances {
  // DC offset: channel c's offset is drawn once, from the seed, uniformly in
  // ±[0.5, 1]·offset_v (random sign); the same for every shot of the bench,
  // as a real scope's offset is until it is recalibrated. Volts, >= 0.
  double offset_v = 0.0;
  // Another bench's offsets (issue 40): each shot's, per channel, moved by a
  // further uniform ±offset_shot_v drawn per shot (AC-coupled front ends,
  // auto-zero between shots). Volts, >= 0; key "offset_shot".
  double offset_shot_v = 0.0;
  // Mains pickup, amplitude (peak) of the fundamental on each channel, volts:
  // hum_v·[sin θ + 0.30·sin 2θ + 0.15·sin 3θ], θ = 2π·mains_hz·t + φ, with φ
  // uniform in [0, 2π) drawn per channel and per shot (shots are not
  // synchronous with the mains). The harmonics are locked to the fundamental
  // (one distorted mains waveform seen at a random instant).
  double hum_v = 0.0;
  double mains_hz = 50.0;  // 50 or 60
  // Pink (1/f) noise per channel, rms as a fraction of the clean channel's
  // std (the seed's definition of noise_rel), Voss–McCartney (pink_noise()).
  double pink_rel = 0.0;
  // Warm-up drift over the N shots of a capture: shot i gets the factor
  // 1 + drift_rel·(i/(N − 1) − 0.5)·s_k on YE11, εT33 and d31, with the signs
  // s_k of kDriftSign (a warming PZT softens, its permittivity and |d31| grow).
  // N comes from the runner (SimBench::set_capture_position); a bench that is
  // never told its capture applies no drift (and counts its acquisitions as
  // the shot index of the step). |drift_rel| < 2.
  double drift_rel = 0.0;
  // The tube touched or reclamped: εT33 and d31 are (1 + step_rel) times their
  // value from shot step_after_shot + 1 on (0-based shot indices, as the
  // capture's /shots/000000…). step_rel > −1; step_after_shot >= 0.
  double step_rel = 0.0;
  int step_after_shot = 0;
  // Trigger jitter: each shot's record (both channels together) is delayed
  // against the excitation by d samples, d uniform in ±jitter_samples: the
  // DAQ samples at t_k − d/fs instead of t_k. The physics is evaluated at
  // those instants (the simulation allows any sampling instants), so the
  // sub-sample shift is exact, not an interpolation. Samples, >= 0.
  double jitter_samples = 0.0;

  bool any() const;
  bool changes_dut() const { return drift_rel != 0.0 || step_rel != 0.0; }
  // Throws std::invalid_argument naming the field.
  void validate() const;
  bool operator==(const Disturbances&) const = default;
};

// Drift signs s_k of YE11, εT33 and d31 (d31 is negative: +1 makes |d31| grow).
inline constexpr ConstantFactors kDriftSign{-1.0, +1.0, +1.0};

// "offset=V,hum=V[,mains=50|60],pink=PCT,drift=PCT,step=PCT@SHOT,jitter=SAMPLES",
// any subset in any order ("" = all off); percent for pink, drift and step.
// Throws std::invalid_argument naming the bad key or value.
Disturbances parse_disturbances(const std::string& text);
// The option string of `d` (only the disturbances that are on; "" if none).
std::string to_string(const Disturbances& d);

// The transducer's constants in shot `shot` of a capture of `shots` (shots
// <= 0: unknown, no drift; shots == 1: the drift's midpoint).
ConstantFactors constant_factors(const Disturbances& d, int shot, int shots);

// What the bench applied to one acquisition (recorded in the capture's /truth).
struct ShotDisturbances {
  int shot = 0;                          // the capture's shot index it belongs to
  double hum_phase_rad[2] = {0.0, 0.0};  // φ of each channel
  ConstantFactors factors;               // multipliers of YE11, εT33, d31
  double jitter_samples = 0.0;           // delay of the record against the excitation (d above)
};

// The capture's /truth (never read by estimators), only when d.any(): the
// settings and the channels' offsets as numbers, and what each recorded shot
// got as per-shot series (index = the shot's position in the capture).
using TruthNumbers = std::vector<std::pair<std::string, double>>;
using TruthSeries = std::vector<std::pair<std::string, std::vector<double>>>;
TruthNumbers disturbance_truth(const Disturbances& d, double offset_v1, double offset_v2);
TruthSeries disturbance_series(const std::vector<ShotDisturbances>& shots);

// One mains-hum waveform (unit fundamental amplitude) at time t, phase φ.
double mains_waveform(double t, double mains_hz, double phase_rad);

// n samples of pink noise with unit variance, Voss–McCartney: R rows of
// white Gaussian values, row r redrawn every 2^(r+1) samples (when the sample
// counter has r trailing zeros), plus a fresh white value every sample; the
// sum has a 1/f spectrum from fs/2^(R+1) up to a few tenths of fs/2. R is
// two more than the record needs (2^(R−2) >= n), so the 1/f holds down to
// the record's lowest frequency and below (the slowest rows act as a slowly
// wandering offset, as a real 1/f source's do).
std::vector<double> pink_noise(std::size_t n, std::mt19937_64& rng);

}  // namespace piezo::drivers::sim
