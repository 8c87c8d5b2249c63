#pragma once
// Test double for the simulated bench's physics: the transducer as an ideal
// capacitor C behind R1, integrated exactly for a piecewise-linear v1
// (first-order-hold discretisation of v2' = (v1 − v2)/(R1·C)).
#include <cmath>

#include "drivers/sim/bench_physics.hpp"

namespace piezo::test {

class RcPhysics : public drivers::sim::BenchPhysics {
 public:
  RcPhysics(double r1, double c) : r1_(r1), c_(c) {}
  // Exact for piecewise-linear v1: over a segment of length h with slope m,
  // v2(t0+h) = e·v2 + (1−e)·v1(t0) + m·(h − τ(1−e)), e = exp(−h/τ).
  std::vector<double> respond(const drivers::sim::PiecewiseLinear& v1,
                              std::span<const double> times) override {
    const double tau = r1_ * c_;
    std::vector<double> out(times.size());
    double t = v1.t.front(), x = 0.0;  // at rest before the first knot
    std::size_t j = 0;  // next knot index
    auto advance = [&](double t_to) {  // integrate from t to t_to across knots
      while (t < t_to) {
        while (j < v1.t.size() && v1.t[j] <= t) ++j;
        double seg_end = j < v1.t.size() ? std::min(v1.t[j], t_to) : t_to;
        double u0 = j == 0 ? v1.v.front() : (j < v1.t.size() ? v1.at(t) : v1.v.back());
        double u1 = j < v1.t.size() ? v1.at(seg_end - 0.0) : v1.v.back();
        if (j < v1.t.size() && seg_end == v1.t[j]) {  // left limit at the knot
          double ta = v1.t[j - 1], tb = v1.t[j];
          u1 = v1.v[j - 1] + (seg_end - ta) / (tb - ta) * (v1.v[j] - v1.v[j - 1]);
        }
        double h = seg_end - t;
        double e = std::exp(-h / tau), m = (u1 - u0) / h;
        x = e * x + (1.0 - e) * u0 + m * (h - tau * (1.0 - e));
        t = seg_end;
      }
    };
    for (std::size_t k = 0; k < times.size(); ++k) {
      advance(times[k]);
      out[k] = x;
    }
    return out;
  }
  std::vector<std::pair<std::string, double>> truth() const override {
    return {{"capacitance_f", c_}, {"r1_true_ohm", r1_}};
  }
  std::string description() const override { return "test RC: ideal capacitor"; }

 private:
  double r1_, c_;
};

}  // namespace piezo::test
