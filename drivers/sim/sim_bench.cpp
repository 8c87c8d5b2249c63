#include "drivers/sim/sim_bench.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

namespace piezo::drivers::sim {

SimBench::SimBench(std::unique_ptr<BenchPhysics> physics, DaqImperfections daq, std::uint64_t seed,
                   FaultPlan faults, Disturbances disturbances)
    : physics_(std::move(physics)), imp_(daq), seed_(seed), rng_(seed), faults_(faults),
      dist_(disturbances), dist_rng_(seed ^ 0xD1B54A32D192ED03ull) {
  if (!physics_) throw std::invalid_argument("SimBench: null physics");
  if (imp_.adc_bits < 4 || imp_.adc_bits > 16)
    throw std::invalid_argument("SimBench: adc_bits must be 4..16");
  dist_.validate();
  if (dist_.offset_v > 0) {  // once per bench: a scope's offset is the same for every shot
    std::uniform_real_distribution<double> magnitude(0.5, 1.0), unit(0.0, 1.0);
    for (double& o : offset_v_) {
      const double m = magnitude(dist_rng_) * dist_.offset_v;
      o = unit(dist_rng_) < 0.5 ? -m : m;
    }
  }
  if (dist_.changes_dut()) {
    const std::string why = physics_->set_constant_factors(ConstantFactors{});
    if (!why.empty()) throw std::invalid_argument("SimBench: drift/step disturbances: " + why);
  }
}

void SimBench::set_capture_position(int shot, int shots) {
  if (shot < 0 || shots < 1 || shot >= shots)
    throw std::invalid_argument("SimBench::set_capture_position: need 0 <= shot < shots");
  std::lock_guard lock(mu_);
  capture_shot_ = shot;
  capture_shots_ = shots;
}

ShotDisturbances SimBench::last_disturbances() {
  std::lock_guard lock(mu_);
  return last_;
}

std::string SimBench::select_dut(const DutSelection& d) {
  using K = DutSelection::Kind;
  if (d.kind == K::Load && !(std::isfinite(d.load_ohm) && d.load_ohm > 0))
    return "load resistance must be positive";
  if (d.kind == K::Load && !(std::isfinite(d.load_parallel_f) && d.load_parallel_f >= 0))
    return "load capacitance must be >= 0";
  std::string why = physics_->select_dut(d);
  if (why.empty()) dut_ = d;
  return why;
}

double PiecewiseLinear::at(double time) const {
  if (t.empty()) return 0.0;
  if (time < t.front()) return v.front();
  auto it = std::upper_bound(t.begin(), t.end(), time);  // first knot after `time`
  if (it == t.end()) return v.back();
  std::size_t j = static_cast<std::size_t>(it - t.begin());  // t[j-1] <= time < t[j]
  double t0 = t[j - 1], t1 = t[j];
  double f = (time - t0) / (t1 - t0);
  return v[j - 1] + f * (v[j] - v[j - 1]);
}

// The AWG output: a sampled generator interpolating linearly between its
// samples, the idle level (offset) being its sample before the burst and after
// it. So the burst's first sample is reached by a ramp from t = −Δt and left
// by a ramp to the offset: no jump the DAQ's samples could not represent (a
// jump at t = 0 would sit half a sample away from the ramp that the samples
// imply, which a divider estimate reads as a 0.5/fs skew between channels).
PiecewiseLinear SimBench::generator_knots(double t_begin, double t_end) const {
  PiecewiseLinear w;
  const double off = awg_.offset_v;
  const double dt_awg = awg_.arb_rate_hz > 0 ? 1.0 / awg_.arb_rate_hz : 0.0;
  w.t.push_back(std::min(t_begin, -dt_awg));
  w.v.push_back(off);
  if (awg_.output_on && !awg_.arb.empty()) {
    const double half = 0.5 * awg_.vpp, dt = dt_awg;
    w.t.push_back(-dt);
    w.v.push_back(off);
    for (std::size_t i = 0; i < awg_.arb.size(); ++i) {
      double ti = static_cast<double>(i) * dt;
      if (ti > t_end + dt) break;
      w.t.push_back(ti);
      w.v.push_back(off + half * awg_.arb[i]);
    }
    // After the last arb sample the output ramps back to the offset over one sample period.
    w.t.push_back(w.t.back() + dt);
    w.v.push_back(off);
  }
  if (w.t.back() < t_end) {
    w.t.push_back(t_end);
    w.v.push_back(off);
  }
  return w;
}

ShotDisturbances SimBench::draw_disturbances() {
  ShotDisturbances sd;
  sd.shot = capture_shot_ >= 0 ? capture_shot_ : acquisitions_;
  if (!dist_.any()) return sd;
  if (dist_.hum_v > 0) {
    std::uniform_real_distribution<double> phase(0.0, 2.0 * M_PI);
    for (double& p : sd.hum_phase_rad) p = phase(dist_rng_);
  }
  if (dist_.jitter_samples > 0) {
    std::uniform_real_distribution<double> d(-dist_.jitter_samples, dist_.jitter_samples);
    sd.jitter_samples = d(dist_rng_);
  }
  if (dist_.changes_dut()) {
    sd.factors = constant_factors(dist_, sd.shot, capture_shot_ >= 0 ? capture_shots_ : 0);
    if (!(sd.factors == factors_)) {
      const std::string why = physics_->set_constant_factors(sd.factors);
      if (!why.empty())
        throw std::runtime_error("SimBench: shot " + std::to_string(sd.shot) + ": " + why);
      factors_ = sd.factors;
    }
  }
  return sd;
}

std::vector<double> SimBench::additive_disturbance(int ch, const ShotDisturbances& sd,
                                                   const std::vector<double>& t, double clean_std) {
  double off = offset_v_[ch];
  if (dist_.offset_shot_v > 0) {  // this shot's own, per channel
    std::uniform_real_distribution<double> u(-dist_.offset_shot_v, dist_.offset_shot_v);
    off += u(dist_rng_);
  }
  std::vector<double> a(t.size(), off);
  if (dist_.hum_v > 0)
    for (std::size_t k = 0; k < t.size(); ++k)
      a[k] += dist_.hum_v * mains_waveform(t[k], dist_.mains_hz, sd.hum_phase_rad[ch]);
  if (dist_.pink_rel > 0) {
    const std::vector<double> p = pink_noise(t.size(), dist_rng_);
    const double scale = dist_.pink_rel * clean_std;
    for (std::size_t k = 0; k < t.size(); ++k) a[k] += scale * p[k];
  }
  return a;
}

void SimBench::fire() {
  if (!daq_.armed || !awg_.output_on) return;
  const std::size_t n = daq_.points;
  const double fs = daq_.sample_rate_hz;
  const ShotDisturbances sd = draw_disturbances();
  // Time of sample 0 relative to the trigger; trigger jitter delays the record
  // against the excitation by d samples: the DAQ samples d/fs earlier.
  const double t0 = daq_.position_s - sd.jitter_samples / fs;

  // Channel 1 samples at t_k; channel 2 at t_k - skew (it records late).
  std::vector<double> t1(n), t2(n);
  for (std::size_t k = 0; k < n; ++k) {
    t1[k] = t0 + static_cast<double>(k) / fs;
    t2[k] = t1[k] - imp_.channel_skew_s;
  }
  const double t_begin = std::min(t1.front(), t2.front()) - 1.0 / fs;
  const double t_end = std::max(t1.back(), t2.back());
  PiecewiseLinear gen = generator_knots(t_begin, t_end);
  std::vector<double> clean[2];
  clean[0].resize(n);
  for (std::size_t k = 0; k < n; ++k) clean[0][k] = gen.at(t1[k]);
  clean[1] = physics_->respond(gen, t2);
  for (double& x : clean[1]) x *= 1.0 + imp_.channel_gain;

  std::normal_distribution<double> gauss(0.0, 1.0);
  const int bits = imp_.adc_bits;
  const double max_code = std::ldexp(1.0, bits - 1) - 1.0;
  for (int ch = 0; ch < 2; ++ch) {
    auto& x = clean[ch];
    double mean = std::accumulate(x.begin(), x.end(), 0.0) / static_cast<double>(n);
    double var = 0;
    for (double s : x) var += (s - mean) * (s - mean);
    const double clean_std = std::sqrt(var / static_cast<double>(n));
    double sigma = imp_.noise_rel[ch] * clean_std + imp_.noise_v[ch];
    // Offset, hum and pink noise enter at the DAQ's input, before quantisation
    // and clipping, on the nominal sampling instants (the hum's phase is
    // random anyway).
    std::vector<double> extra;
    if (dist_.any()) {
      std::vector<double> tn(n);
      for (std::size_t k = 0; k < n; ++k) tn[k] = daq_.position_s + static_cast<double>(k) / fs;
      extra = additive_disturbance(ch, sd, tn, clean_std);
    }
    const double half_scale = 0.5 * daq_.full_scale_v[ch];
    const double lsb = half_scale / (max_code + 1.0);
    const double word_step = std::ldexp(1.0, 16 - bits);
    daq_.codes[ch].resize(n);
    for (std::size_t k = 0; k < n; ++k) {
      double v = x[k];
      if (!extra.empty()) v += extra[k];
      v += (sigma > 0 ? sigma * gauss(rng_) : 0.0);
      double code = std::clamp(std::round(v / lsb), -max_code - 1.0, max_code);  // range clipping
      daq_.codes[ch][k] = static_cast<std::int16_t>(code * word_step);
    }
    daq_.yincrement[ch] = lsb / word_step;
  }
  daq_.armed = false;
  daq_.done = true;
  last_ = sd;
  ++acquisitions_;
}

}  // namespace piezo::drivers::sim
