#include "model/bench_response.hpp"

#include <cmath>
#include <stdexcept>

namespace piezo::model {

using cd = std::complex<double>;

cd lossy_capacitance(double c, double tan_delta, double omega) {
  if (tan_delta == 0.0) return c;
  if (!(omega > 0)) throw std::invalid_argument("lossy_capacitance: needs omega > 0");
  const double delta = std::atan(tan_delta);
  return c * std::pow(omega / (2 * M_PI * kDielectricLossRefHz), -2.0 * delta / M_PI) * std::polar(1.0, -delta);
}

cd port_capacitance(const ModalPortModel& port, const EffectSet& fx, double omega) {
  if (fx.dielectric_loss == 0.0) return port.c_clamped + port.c_residual;
  const cd phi = fx.dielectric_constant_phase ? lossy_capacitance(1.0, fx.dielectric_loss, omega)
                                              : cd(1.0, -fx.dielectric_loss);
  return port.c_clamped * (1.0 + port.eps_t_over_s * (phi - 1.0)) + port.c_residual;
}

cd tube_admittance(const ModalPortModel& port, const RayleighDamping& d, const EffectSet& fx,
                   double omega, double elastic_loss) {
  cd q = port_capacitance(port, fx, omega);
  for (const auto& m : port.modes) {
    const double ck = d.alpha + d.beta * m.kappa + 2.0 * fx.mechanical_damping * m.omega;
    // p²/(ω_k² − ω² + jωc_k), the real-over-complex division written out
    // (std::complex's general division is a libgcc call, a tenth of a fit).
    const double re = m.omega * m.omega - omega * omega, im = omega * ck + elastic_loss * m.kappa;
    const double s = m.participation * m.participation / (re * re + im * im);
    q += cd(s * re, -s * im);
  }
  return cd(0.0, omega) * q;
}

cd recorded_transfer(cd y_tube, const EffectSet& fx, double r1_nominal_ohm, double omega) {
  if (!(r1_nominal_ohm > 0)) throw std::invalid_argument("recorded_transfer: R1 must be positive");
  // Y_n = 1/Z_a + jωC_p + 1/R_daq with Z_a = 1/Y_t + R_s; H = 1/(1 + R1·Y_n).
  cd y = fx.series_resistance_ohm > 0 ? y_tube / (1.0 + fx.series_resistance_ohm * y_tube) : y_tube;
  y += cd(0.0, omega * fx.parallel_capacitance_f);
  if (std::isfinite(fx.daq_input_resistance_ohm)) y += 1.0 / fx.daq_input_resistance_ohm;
  const cd h = 1.0 / (1.0 + r1_nominal_ohm * (1.0 + fx.r1_tolerance) * y);
  return h * (1.0 + fx.channel_gain) * std::exp(cd(0.0, -omega * fx.channel_skew_s));
}

cd reported_impedance(cd y_tube, const EffectSet& fx, double r1_nominal_ohm, double omega) {
  if (!(r1_nominal_ohm > 0)) throw std::invalid_argument("reported_impedance: R1 must be positive");
  const cd hm = recorded_transfer(y_tube, fx, r1_nominal_ohm, omega);
  return r1_nominal_ohm * hm / (1.0 - hm);
}

std::vector<cd> bench_impedance(const ModalPortModel& port, const RayleighDamping& d,
                                const EffectSet& fx, double r1_nominal_ohm,
                                std::span<const double> f_hz, double elastic_loss) {
  std::vector<cd> z(f_hz.size());
  for (std::size_t i = 0; i < f_hz.size(); ++i) {
    const double w = 2 * M_PI * f_hz[i];
    z[i] = reported_impedance(tube_admittance(port, d, fx, w, elastic_loss), fx, r1_nominal_ohm, w);
  }
  return z;
}

}  // namespace piezo::model
