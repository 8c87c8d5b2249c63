// The divider bench with a calibration standard at the terminals instead of
// the tube (simulator only, selected by SIM:DUT): the same fixture as for the
// tube (divider_state_space.hpp),
//
//   v1 ──[R1]──● v2 ──[Rs]──● t ── standard ── GND      open:  nothing at t
//              ├─ Cp ─ GND                               short: t joined to GND
//              └─ Rd ─ GND                               load:  RL ∥ CL at t
//
// built by nodal analysis: node voltages with a capacitance to ground are
// states, the others are eliminated algebraically (Kron reduction), so every
// combination of zero and non-zero element values gives a proper system.
#include <cmath>
#include <stdexcept>

#include "acquisition/divider_state_space.hpp"

namespace piezo::acq {

void DividerStateSpace::build_standard(const BenchCircuit& k) {
  using K = drivers::sim::DutSelection::Kind;
  const auto& dut = k.dut;
  if (dut.kind == K::Load &&
      !(dut.load_ohm > 0 && std::isfinite(dut.load_ohm) && dut.load_parallel_f >= 0))
    throw std::invalid_argument("DividerStateSpace: the load standard needs R > 0 and C >= 0");
  const double g1 = 1.0 / k.r1_ohm;
  const double gd =
      std::isfinite(k.daq_input_resistance_ohm) ? 1.0 / k.daq_input_resistance_ohm : 0.0;
  const double rs = k.series_resistance_ohm;

  if (dut.kind == K::Short && rs == 0.0) {  // v2 is held at ground: no dynamics, no output
    a_.resize(0, 0);
    b_.resize(0);
    c_.resize(0);
    d_ = 0.0;
    return;
  }
  // Nodes: 0 = v2; 1 = the terminal node t when it is a node of its own.
  const bool t_node = dut.kind == K::Load && rs > 0;
  const int nn = t_node ? 2 : 1;
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(nn, nn);  // nodal conductances
  Eigen::VectorXd cap = Eigen::VectorXd::Zero(nn), bin = Eigen::VectorXd::Zero(nn);
  g(0, 0) += g1 + gd;
  bin(0) = g1;  // current g1·v1 injected by the generator through R1
  cap(0) = k.parallel_capacitance_f;
  if (dut.kind == K::Short) g(0, 0) += 1.0 / rs;
  if (dut.kind == K::Load) {
    const double gl = 1.0 / dut.load_ohm;
    if (t_node) {
      const double gs = 1.0 / rs;
      g(0, 0) += gs;
      g(0, 1) -= gs;
      g(1, 0) -= gs;
      g(1, 1) += gs + gl;
      cap(1) = dut.load_parallel_f;
    } else {
      g(0, 0) += gl;
      cap(0) += dut.load_parallel_f;
    }
  }

  std::vector<int> dyn, alg;
  for (int i = 0; i < nn; ++i) (cap(i) > 0 ? dyn : alg).push_back(i);
  const int nd = static_cast<int>(dyn.size()), na = static_cast<int>(alg.size());
  auto sub = [&](const std::vector<int>& r, const std::vector<int>& c) {
    Eigen::MatrixXd m(r.size(), c.size());
    for (std::size_t i = 0; i < r.size(); ++i)
      for (std::size_t j = 0; j < c.size(); ++j)
        m(static_cast<int>(i), static_cast<int>(j)) = g(r[i], c[j]);
    return m;
  };
  auto part = [&](const std::vector<int>& r) {
    Eigen::VectorXd v(r.size());
    for (std::size_t i = 0; i < r.size(); ++i) v(static_cast<int>(i)) = bin(r[i]);
    return v;
  };
  // Algebraic nodes: G_aa·v_a + G_ad·v_d = b_a·u  ⇒  v_a = M·v_d + m·u.
  Eigen::MatrixXd m_ad = Eigen::MatrixXd::Zero(na, nd);
  Eigen::VectorXd m_u = Eigen::VectorXd::Zero(na);
  if (na > 0) {
    const auto lu =
        sub(alg, alg).partialPivLu();  // every node reaches ground or v1 through a conductance
    if (nd > 0) m_ad = -lu.solve(sub(alg, dyn));  // (a purely resistive standard has no dynamic node)
    m_u = lu.solve(part(alg));
  }
  // Dynamic nodes: C_d·v_d' = −G_dd·v_d − G_da·v_a + b_d·u, in √C·v coordinates (balanced).
  a_ = Eigen::MatrixXd::Zero(nd, nd);
  b_ = Eigen::VectorXd::Zero(nd);
  c_ = Eigen::RowVectorXd::Zero(nd);
  d_ = 0.0;
  if (nd > 0) {
    const Eigen::MatrixXd g_da = sub(dyn, alg);
    const Eigen::MatrixXd a_v = -sub(dyn, dyn) - g_da * m_ad;
    const Eigen::VectorXd b_v = part(dyn) - g_da * m_u;
    for (int i = 0; i < nd; ++i) {
      const double si = std::sqrt(cap(dyn[i]));
      for (int j = 0; j < nd; ++j) a_(i, j) = a_v(i, j) / (si * std::sqrt(cap(dyn[j])));
      b_(i) = b_v(i) / si;
    }
  }
  // Output v2 (node 0).
  for (int i = 0; i < nd; ++i)
    if (dyn[i] == 0) c_(i) = 1.0 / std::sqrt(cap(0));
  for (int i = 0; i < na; ++i)
    if (alg[i] == 0) {
      for (int j = 0; j < nd; ++j) c_(j) = m_ad(i, j) / std::sqrt(cap(dyn[j]));
      d_ = m_u(i);
    }
}

}  // namespace piezo::acq
