#include "model/bench_response.hpp"

#include <cmath>
#include <stdexcept>
#include <vector>

#include "numerics/complex_division.hpp"
#include "numerics/simd_clones.hpp"

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

PIEZO_SIMD_CLONES  // (its modal loop is element-wise over the bins: numerics/simd_clones.hpp)
void tube_admittances(const ModalPortModel& port, const RayleighDamping& d, const EffectSet& fx,
                      std::span<const double> omega, double elastic_loss, std::span<cd> y) {
  const std::size_t n = omega.size();
  if (y.size() < n) throw std::invalid_argument("tube_admittances: y shorter than omega");
  thread_local std::vector<double> qr, qi;
  qr.resize(n);
  qi.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const cd q = port_capacitance(port, fx, omega[i]);
    qr[i] = q.real();
    qi[i] = q.imag();
  }
  const double* w = omega.data();
  double* r = qr.data();
  double* im_q = qi.data();
  for (const auto& m : port.modes) {  // as tube_admittance, term by term
    const double ck = d.alpha + d.beta * m.kappa + 2.0 * fx.mechanical_damping * m.omega;
    const double w2 = m.omega * m.omega, p2 = m.participation * m.participation, loss = elastic_loss * m.kappa;
    for (std::size_t i = 0; i < n; ++i) {
      const double re = w2 - w[i] * w[i], im = w[i] * ck + loss;
      const double s = p2 / (re * re + im * im);
      r[i] += s * re;
      im_q[i] += -s * im;
    }
  }
  for (std::size_t i = 0; i < n; ++i) y[i] = cd(0.0, w[i]) * cd(r[i], im_q[i]);
}

namespace {
// The catalogue's entries of each circuit/DAQ stage, found once (this is the
// fits' inner loop: a few entries, no search).
constexpr int kStages = static_cast<int>(EffectStage::channel2) + 1;
struct StageEntries {
  std::vector<const EffectInfo*> at[kStages];
  StageEntries() {
    for (const auto& e : effect_catalogue()) at[static_cast<int>(e.stage)].push_back(&e);
  }
};
const std::vector<const EffectInfo*>& entries(EffectStage s) {
  static const StageEntries all;
  return all.at[static_cast<int>(s)];
}
// Whether e is present in fx (its value not the neutral one).
bool present(const EffectInfo& e, const EffectSet& fx) {
  static const EffectSet neutral;
  return fx.*(e.field) != neutral.*(e.field);
}
}  // namespace

namespace {
// The circuit/DAQ effects of fx, stage by stage (the catalogue's order; the
// channel-2 factors from its last to its first: the order this product was
// first written in, only the rounding depends on it).
struct PresentEffects {
  std::vector<const EffectInfo*> series, shunt, r1, daq;
  explicit PresentEffects(const EffectSet& fx) {
    for (const EffectInfo* e : entries(EffectStage::series))
      if (present(*e, fx)) series.push_back(e);
    for (const EffectInfo* e : entries(EffectStage::shunt))
      if (present(*e, fx)) shunt.push_back(e);
    for (const EffectInfo* e : entries(EffectStage::r1))
      if (present(*e, fx)) r1.push_back(e);
    const auto& d = entries(EffectStage::channel2);
    for (auto it = d.rbegin(); it != d.rend(); ++it)
      if (present(**it, fx)) daq.push_back(*it);
  }
};

cd transfer_with(const PresentEffects& pe, cd y_tube, const EffectSet& fx, double r1_nominal_ohm, double omega) {
  // Each circuit and DAQ effect by its catalogue term (model/effects.hpp):
  // Z_a = 1/Y_t + ΣZ_series, Y_n = 1/Z_a + ΣY_shunt, H = 1/(1 + R1·Πf_r1·Y_n),
  // H' = H·Πf_channel2.
  cd y = y_tube;
  for (const EffectInfo* e : pe.series)
    if (const cd z = e->term(fx.*(e->field), omega); z != 0.0)
      y = z.imag() == 0.0 ? numerics::divide(y, 1.0 + z.real() * y)  // a real term: a real product
                          : numerics::divide(y, 1.0 + z * y);
  for (const EffectInfo* e : pe.shunt) y += e->term(fx.*(e->field), omega);
  double r1 = r1_nominal_ohm;
  for (const EffectInfo* e : pe.r1) r1 *= e->term(fx.*(e->field), omega).real();
  cd h = numerics::reciprocal(1.0 + r1 * y);
  for (const EffectInfo* e : pe.daq) {
    const cd f = e->term(fx.*(e->field), omega);
    if (f.imag() == 0.0) h *= f.real();  // (the same numbers, without a complex product's NaN checks)
    else h *= f;
  }
  return h;
}
}  // namespace

cd recorded_transfer(cd y_tube, const EffectSet& fx, double r1_nominal_ohm, double omega) {
  if (!(r1_nominal_ohm > 0)) throw std::invalid_argument("recorded_transfer: R1 must be positive");
  return transfer_with(PresentEffects(fx), y_tube, fx, r1_nominal_ohm, omega);
}

void recorded_transfers(std::span<cd> y, const EffectSet& fx, double r1_nominal_ohm, std::span<const double> omega) {
  if (!(r1_nominal_ohm > 0)) throw std::invalid_argument("recorded_transfers: R1 must be positive");
  if (y.size() != omega.size()) throw std::invalid_argument("recorded_transfers: y and omega differ in size");
  const PresentEffects pe(fx);
  for (std::size_t i = 0; i < y.size(); ++i) y[i] = transfer_with(pe, y[i], fx, r1_nominal_ohm, omega[i]);
}

cd reported_impedance(cd y_tube, const EffectSet& fx, double r1_nominal_ohm, double omega) {
  if (!(r1_nominal_ohm > 0)) throw std::invalid_argument("reported_impedance: R1 must be positive");
  const cd hm = recorded_transfer(y_tube, fx, r1_nominal_ohm, omega);
  return numerics::divide(r1_nominal_ohm * hm, 1.0 - hm);
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
