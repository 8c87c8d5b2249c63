#include "model/transient.hpp"

#include <unsupported/Eigen/MatrixFunctions>

#include <cmath>
#include <stdexcept>

namespace piezo::model {

namespace {

// Modes that couple to the electrode; uncoupled modes (antisymmetric, p = 0)
// cannot be excited and are left out.
std::vector<PortMode> coupled_modes(const ModalPortModel& port) {
  std::vector<PortMode> m;
  for (const auto& k : port.modes)
    if (k.omega > 0 && k.participation * k.participation / (k.omega * k.omega) >
                           1e-12 * port.c_static)
      m.push_back(k);
  return m;
}

void check_port(const ModalPortModel& port, const char* fn) {
  const double ce = port.c_clamped + port.c_residual;
  if (!(port.c_clamped > 0) || !(ce > 0))
    throw std::invalid_argument(std::string(fn) + ": port model has no positive capacitance");
}

// Physical state s = [voltages…, q_1, i_1, …, q_K, i_K] is scaled to energy
// coordinates x = T s (T = √C for voltages, ω_k/p_k for q_k, 1/p_k for i_k),
// which makes A nearly skew-symmetric and the matrix exponential well conditioned.
struct Physical {
  Eigen::MatrixXd a;
  Eigen::VectorXd b;
  Eigen::RowVectorXd c;
  double d = 0;
  Eigen::VectorXd t;  // scaling
  DiscreteLti discretise(double dt) const {
    const Eigen::VectorXd ti = t.cwiseInverse();
    const Eigen::MatrixXd as = t.asDiagonal() * a * ti.asDiagonal();
    return DiscreteLti(as, t.cwiseProduct(b), c * ti.asDiagonal(), d, dt);
  }
};

// Adds the motional branches driven by the voltage state `iv` and feeding their
// current into the equation of state `iv` with capacitance `cap` (i.e. C v̇ −= Σ i_k).
void add_modes(Physical& s, const std::vector<PortMode>& modes, const RayleighDamping& damp,
               int first, int iv, double cap) {
  for (std::size_t k = 0; k < modes.size(); ++k) {
    const auto& m = modes[k];
    const int q = first + 2 * static_cast<int>(k), i = q + 1;
    const double ck = damp.alpha + damp.beta * m.kappa;
    s.a(q, i) = 1.0;                                      // q̇ = i
    s.a(i, iv) = m.participation * m.participation;       // i̇ = p² v − ω² q − c i
    s.a(i, q) = -m.omega * m.omega;
    s.a(i, i) = -ck;
    if (iv >= 0 && cap > 0) s.a(iv, i) = -1.0 / cap;
    s.t[q] = m.omega / std::abs(m.participation);
    s.t[i] = 1.0 / std::abs(m.participation);
  }
}

}  // namespace

void DividerCircuit::validate() const {
  const char* fn = "DividerCircuit::validate";
  if (!(r1_ohm > 0) || !std::isfinite(r1_ohm))
    throw std::invalid_argument(std::string(fn) + ": r1_ohm must be finite and > 0");
  if (!(c_parallel_f >= 0) || !std::isfinite(c_parallel_f))
    throw std::invalid_argument(std::string(fn) + ": c_parallel_f must be finite and >= 0");
  if (!(r_lead_ohm >= 0) || !std::isfinite(r_lead_ohm))
    throw std::invalid_argument(std::string(fn) + ": r_lead_ohm must be finite and >= 0");
  if (!(r_daq_ohm > 0))
    throw std::invalid_argument(std::string(fn) + ": r_daq_ohm must be > 0 (infinity: absent)");
}

DiscreteLti::DiscreteLti(const Eigen::MatrixXd& a, const Eigen::VectorXd& b,
                         const Eigen::RowVectorXd& c, double d, double dt)
    : c_(c), d_(d) {
  if (!(dt > 0) || !std::isfinite(dt)) throw std::invalid_argument("DiscreteLti: dt must be > 0");
  const int n = static_cast<int>(a.rows());
  if (a.cols() != n || b.size() != n || c.size() != n)
    throw std::invalid_argument("DiscreteLti: inconsistent dimensions");
  // exp([[A, B, 0], [0, 0, 1/h], [0, 0, 0]]·h) = [[Φ, Γ0, Γ1], …]: u(t) = u_n + w·t/h.
  Eigen::MatrixXd m = Eigen::MatrixXd::Zero(n + 2, n + 2);
  m.topLeftCorner(n, n) = a * dt;
  m.block(0, n, n, 1) = b * dt;
  m(n, n + 1) = 1.0;
  const Eigen::MatrixXd e = m.exp();
  phi_ = e.topLeftCorner(n, n);
  g0_ = e.block(0, n, n, 1);
  g1_ = e.block(0, n + 1, n, 1);
}

std::vector<double> DiscreteLti::run(std::span<const double> u) const {
  std::vector<double> y(u.size());
  Eigen::VectorXd x = Eigen::VectorXd::Zero(phi_.rows()), xn(phi_.rows());
  for (std::size_t k = 0; k < u.size(); ++k) {
    y[k] = c_.dot(x) + d_ * u[k];
    if (k + 1 < u.size()) {
      xn.noalias() = phi_ * x;
      xn += g0_ * u[k] + g1_ * (u[k + 1] - u[k]);
      x.swap(xn);
    }
  }
  return y;
}

DividerSimulator::DividerSimulator(const ModalPortModel& port, const RayleighDamping& damping,
                                   const DividerCircuit& cc, double fs) {
  const char* fn = "DividerSimulator";
  check_port(port, fn);
  damping.validate();
  cc.validate();
  if (!(fs > 0) || !std::isfinite(fs)) throw std::invalid_argument("DividerSimulator: sample rate must be > 0");
  const auto modes = coupled_modes(port);
  const int nm = 2 * static_cast<int>(modes.size());
  const double ce = port.c_clamped + port.c_residual;
  const double g1 = 1.0 / cc.r1_ohm, gd = 1.0 / cc.r_daq_ohm;  // gd = 0 when R_daq = ∞
  Physical s;
  if (cc.r_lead_ohm == 0.0) {
    // One node: (Ce + Cp) v̇ = (v1 − v)/R1 − v/Rd − Σ i_k.
    const double ct = ce + cc.c_parallel_f;
    s.a = Eigen::MatrixXd::Zero(1 + nm, 1 + nm);
    s.b = Eigen::VectorXd::Zero(1 + nm);
    s.c = Eigen::RowVectorXd::Zero(1 + nm);
    s.t = Eigen::VectorXd::Ones(1 + nm);
    s.a(0, 0) = -(g1 + gd) / ct;
    s.b[0] = g1 / ct;
    s.c[0] = 1.0;
    s.t[0] = std::sqrt(ct);
    add_modes(s, modes, damping, 1, 0, ct);
  } else if (cc.c_parallel_f > 0) {
    // Two nodes: Cp v̇2 = (v1 − v2)/R1 − v2/Rd − (v2 − vt)/Rl ; Ce v̇t = (v2 − vt)/Rl − Σ i_k.
    const double gl = 1.0 / cc.r_lead_ohm, cp = cc.c_parallel_f;
    s.a = Eigen::MatrixXd::Zero(2 + nm, 2 + nm);
    s.b = Eigen::VectorXd::Zero(2 + nm);
    s.c = Eigen::RowVectorXd::Zero(2 + nm);
    s.t = Eigen::VectorXd::Ones(2 + nm);
    s.a(0, 0) = -(g1 + gd + gl) / cp;
    s.a(0, 1) = gl / cp;
    s.a(1, 0) = gl / ce;
    s.a(1, 1) = -gl / ce;
    s.b[0] = g1 / cp;
    s.c[0] = 1.0;
    s.t[0] = std::sqrt(cp);
    s.t[1] = std::sqrt(ce);
    add_modes(s, modes, damping, 2, 1, ce);
  } else {
    // Node 2 algebraic: v2 = a·v1 + b·vt; Ce v̇t = (v2 − vt)/Rl − Σ i_k.
    const double gl = 1.0 / cc.r_lead_ohm, gsum = g1 + gd + gl;
    const double ka = g1 / gsum, kb = gl / gsum;
    s.a = Eigen::MatrixXd::Zero(1 + nm, 1 + nm);
    s.b = Eigen::VectorXd::Zero(1 + nm);
    s.c = Eigen::RowVectorXd::Zero(1 + nm);
    s.t = Eigen::VectorXd::Ones(1 + nm);
    s.a(0, 0) = (kb - 1.0) * gl / ce;
    s.b[0] = ka * gl / ce;
    s.c[0] = kb;
    s.d = ka;
    s.t[0] = std::sqrt(ce);
    add_modes(s, modes, damping, 1, 0, ce);
  }
  lti_ = s.discretise(1.0 / fs);
}

std::vector<double> DividerSimulator::simulate(std::span<const double> v1) const {
  return lti_.run(v1);
}

ChargeSimulator::ChargeSimulator(const ModalPortModel& port, const RayleighDamping& damping,
                                 double fs) {
  check_port(port, "ChargeSimulator");
  damping.validate();
  if (!(fs > 0) || !std::isfinite(fs)) throw std::invalid_argument("ChargeSimulator: sample rate must be > 0");
  const auto modes = coupled_modes(port);
  const int nm = 2 * static_cast<int>(modes.size());
  // The voltage is the input: i̇_k = p_k² v − ω_k² q_k − c_k i_k, Q = (C0 + C_res) v + Σ q_k.
  Physical s;
  s.a = Eigen::MatrixXd::Zero(nm, nm);
  s.b = Eigen::VectorXd::Zero(nm);
  s.c = Eigen::RowVectorXd::Zero(nm);
  s.t = Eigen::VectorXd::Ones(nm);
  s.d = port.c_clamped + port.c_residual;
  for (std::size_t k = 0; k < modes.size(); ++k) {
    const auto& m = modes[k];
    const int q = 2 * static_cast<int>(k), i = q + 1;
    s.a(q, i) = 1.0;
    s.a(i, q) = -m.omega * m.omega;
    s.a(i, i) = -(damping.alpha + damping.beta * m.kappa);
    s.b[i] = m.participation * m.participation;
    s.c[q] = 1.0;
    s.t[q] = m.omega / std::abs(m.participation);
    s.t[i] = 1.0 / std::abs(m.participation);
  }
  lti_ = s.discretise(1.0 / fs);
}

std::vector<double> ChargeSimulator::simulate(std::span<const double> v) const {
  return lti_.run(v);
}

std::vector<double> simulate_divider(const ModalPortModel& port, const RayleighDamping& damping,
                                     const DividerCircuit& circuit, std::span<const double> v1,
                                     double fs) {
  return DividerSimulator(port, damping, circuit, fs).simulate(v1);
}

std::vector<double> simulate_charge(const ModalPortModel& port, const RayleighDamping& damping,
                                    std::span<const double> v, double fs) {
  return ChargeSimulator(port, damping, fs).simulate(v);
}

std::complex<double> divider_transfer(const ModalPortModel& port, const RayleighDamping& damping,
                                      const DividerCircuit& cc, double f_hz) {
  using cd = std::complex<double>;
  cc.validate();
  const double w = 2.0 * M_PI * f_hz;
  // Same modal set as the simulators (uncoupled modes contribute nothing).
  ModalPortModel p = port;
  p.modes = coupled_modes(port);
  const cd yt = cd(0, w) * p.charge_per_volt(w, damping);                // transducer
  const cd yb = cc.r_lead_ohm > 0 ? yt / (1.0 + cc.r_lead_ohm * yt) : yt;  // + lead
  const cd y2 = yb + cd(0, w * cc.c_parallel_f) + 1.0 / cc.r_daq_ohm;     // node 2 to ground
  return 1.0 / (1.0 + cc.r1_ohm * y2);
}

}  // namespace piezo::model
