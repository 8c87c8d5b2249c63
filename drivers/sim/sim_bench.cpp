#include "drivers/sim/sim_bench.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace piezo::drivers::sim {

SimBench::SimBench(std::unique_ptr<BenchPhysics> physics, DaqImperfections daq, std::uint64_t seed,
                   FaultPlan faults)
    : physics_(std::move(physics)), imp_(daq), seed_(seed), rng_(seed), faults_(faults) {
  if (!physics_) throw std::invalid_argument("SimBench: null physics");
  if (imp_.adc_bits < 4 || imp_.adc_bits > 16)
    throw std::invalid_argument("SimBench: adc_bits must be 4..16");
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

void SimBench::fire() {
  if (!daq_.armed || !awg_.output_on) return;
  const std::size_t n = daq_.points;
  const double fs = daq_.sample_rate_hz;
  const double t0 = daq_.position_s;  // time of sample 0 relative to the trigger

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
    double sigma = imp_.noise_rel[ch] * std::sqrt(var / static_cast<double>(n)) + imp_.noise_v[ch];
    const double half_scale = 0.5 * daq_.full_scale_v[ch];
    const double lsb = half_scale / (max_code + 1.0);
    const double word_step = std::ldexp(1.0, 16 - bits);
    daq_.codes[ch].resize(n);
    for (std::size_t k = 0; k < n; ++k) {
      double v = x[k] + (sigma > 0 ? sigma * gauss(rng_) : 0.0);
      double code = std::clamp(std::round(v / lsb), -max_code - 1.0, max_code);  // range clipping
      daq_.codes[ch][k] = static_cast<std::int16_t>(code * word_step);
    }
    daq_.yincrement[ch] = lsb / word_step;
  }
  daq_.armed = false;
  daq_.done = true;
  ++acquisitions_;
}

}  // namespace piezo::drivers::sim
