#include "acquisition/divider_state_space.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <unsupported/Eigen/MatrixFunctions>

#include "model/bench_response.hpp"

namespace piezo::acq {

std::complex<double> DebyeNetwork::capacitance(double omega) const {
  std::complex<double> c = c_inf;
  for (auto [ci, ti] : branches) c += ci / std::complex<double>(1.0, omega * ti);
  return c;
}

DebyeNetwork debye_network_for_loss(double c, double tan_delta, double f_lo, double f_hi) {
  if (!(c > 0 && f_hi > f_lo && f_lo > 0))
    throw std::invalid_argument("debye_network_for_loss: need C > 0 and 0 < f_lo < f_hi");
  if (tan_delta < 0) throw std::invalid_argument("debye_network_for_loss: tan delta must be >= 0");
  if (tan_delta == 0) return {c, {}};
  return debye_network_fit([&](double w) { return model::lossy_capacitance(c, tan_delta, w); }, f_lo, f_hi);
}

DebyeNetwork debye_network_fit(const std::function<std::complex<double>(double)>& target_of, double f_lo,
                               double f_hi) {
  if (!(f_hi > f_lo && f_lo > 0)) throw std::invalid_argument("debye_network_fit: need 0 < f_lo < f_hi");
  // Relaxation times four per decade, a decade beyond the band on each side;
  // column 0 is C_inf. Rows: real and imaginary parts relative to |C(ω)|.
  std::vector<double> tau;
  for (double t = 0.1 / (2 * M_PI * f_hi); t <= 10.0 / (2 * M_PI * f_lo); t *= std::pow(10.0, 0.25))
    tau.push_back(t);
  const int nw = 240, nb = static_cast<int>(tau.size()) + 1;
  Eigen::MatrixXd a(2 * nw, nb);
  Eigen::VectorXd y(2 * nw);
  for (int i = 0; i < nw; ++i) {
    const double w = 2 * M_PI * f_lo * std::pow(f_hi / f_lo, i / (nw - 1.0));
    const std::complex<double> target = target_of(w);
    const double s = std::abs(target);
    a(2 * i, 0) = 1.0 / s;
    a(2 * i + 1, 0) = 0.0;
    for (int j = 1; j < nb; ++j) {
      const std::complex<double> col = 1.0 / std::complex<double>(1.0, w * tau[j - 1]);
      a(2 * i, j) = col.real() / s;
      a(2 * i + 1, j) = col.imag() / s;
    }
    y(2 * i) = target.real() / s;
    y(2 * i + 1) = target.imag() / s;
  }
  // Non-negative least squares by an active-set loop (Lawson–Hanson style, small problem).
  std::vector<bool> active(nb, true);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(nb);
  for (int it = 0; it < 4 * nb; ++it) {
    std::vector<int> idx;
    for (int j = 0; j < nb; ++j)
      if (active[j]) idx.push_back(j);
    Eigen::MatrixXd sub(2 * nw, static_cast<int>(idx.size()));
    for (std::size_t k = 0; k < idx.size(); ++k) sub.col(static_cast<int>(k)) = a.col(idx[k]);
    Eigen::VectorXd sol = sub.colPivHouseholderQr().solve(y);
    bool neg = false;
    x.setZero();
    for (std::size_t k = 0; k < idx.size(); ++k) {
      if (sol(static_cast<int>(k)) < 0) {
        active[idx[k]] = false;
        neg = true;
      } else {
        x(idx[k]) = sol(static_cast<int>(k));
      }
    }
    if (!neg) break;
  }
  DebyeNetwork net;
  net.c_inf = x(0);
  for (int j = 1; j < nb; ++j)
    if (x(j) > 0) net.branches.emplace_back(x(j), tau[j - 1]);
  if (!(net.c_inf > 0) && !net.branches.empty()) {
    // The fastest branch (τ a decade below the band) is a capacitance over
    // the whole band: it becomes C_inf (the state space needs one at the node).
    auto fastest = std::min_element(net.branches.begin(), net.branches.end(),
                                    [](const auto& a, const auto& b) { return a.second < b.second; });
    net.c_inf += fastest->first;
    net.branches.erase(fastest);
  }
  if (!(net.c_inf > 0)) throw std::runtime_error("debye_network_fit: no positive high-frequency capacitance");
  return net;
}

DividerStateSpace::DividerStateSpace(const model::ModalPortModel& port, const BenchCircuit& k) {
  if (!(k.r1_ohm > 0)) throw std::invalid_argument("DividerStateSpace: R1 must be positive");
  if (k.series_resistance_ohm < 0 || k.parallel_capacitance_f < 0 || !(k.daq_input_resistance_ohm > 0))
    throw std::invalid_argument("DividerStateSpace: circuit values out of range");
  if (k.dut.kind != drivers::sim::DutSelection::Kind::Tube) {  // a calibration standard
    build_standard(k);
    return;
  }
  const double ce = port.c_clamped + port.c_residual;
  if (!(ce > 0)) throw std::invalid_argument("DividerStateSpace: non-positive port capacitance");
  // Second-order terms on the tube node: the port's modes (c_k = α + βκ_k +
  // 2ξ_mω_k + radiation damping) and the parasitic branches (p² = 1/L,
  // ω² = 1/(LC), c = R/L: parasitic_branch.hpp).
  struct Term {
    double omega, participation, damping;
  };
  std::vector<Term> modes;
  for (const auto& m : port.modes)
    if (m.omega > 0 && m.participation != 0.0)
      modes.push_back({m.omega, m.participation,
                       k.damping.alpha + k.damping.beta * m.kappa +
                           2.0 * k.extra_damping_ratio * m.omega + m.radiation_damping});
  for (const auto& b : k.parasitic_branches) {
    if (!(b.r_ohm >= 0 && b.l_h > 0 && b.c_f > 0))
      throw std::invalid_argument(
          "DividerStateSpace: a parasitic branch needs R >= 0, L > 0, C > 0");
    modes.push_back({1.0 / std::sqrt(b.l_h * b.c_f), 1.0 / std::sqrt(b.l_h), b.r_ohm / b.l_h});
  }
  model::EffectSet loss;
  loss.dielectric_loss = k.dielectric_loss;
  loss.dielectric_constant_phase = true;
  if (k.dielectric_loss < 0) throw std::invalid_argument("DividerStateSpace: tan delta must be >= 0");
  const DebyeNetwork net = k.dielectric_loss == 0
                               ? DebyeNetwork{ce, {}}
                               : debye_network_fit([&](double w) { return model::port_capacitance(port, loss, w); });
  const auto& debye = net.branches;
  const double c_inf = net.c_inf;  // Ce itself when there is no loss

  const bool rs = k.series_resistance_ohm > 0, cp = k.parallel_capacitance_f > 0;
  const bool v2_state = rs && cp;
  const int nd = static_cast<int>(debye.size()), nm = static_cast<int>(modes.size());
  const int i_vt = 0, i_v2 = v2_state ? 1 : -1, i_d0 = v2_state ? 2 : 1, i_m0 = i_d0 + nd;
  const int n = i_m0 + 2 * nm;
  a_ = Eigen::MatrixXd::Zero(n, n);
  b_ = Eigen::VectorXd::Zero(n);
  c_ = Eigen::RowVectorXd::Zero(n);
  const double g1 = 1.0 / k.r1_ohm;
  const double gd = std::isfinite(k.daq_input_resistance_ohm) ? 1.0 / k.daq_input_resistance_ohm : 0.0;

  // Rows of Ce_eff·vt' = (currents into the tube's terminal node) are built in `row`, then scaled.
  Eigen::RowVectorXd row = Eigen::RowVectorXd::Zero(n);
  double row_b = 0.0, c_node = c_inf;
  if (!rs) {  // vt = v2: the node holds Ce + Cp; R1, the DAQ input and Debye branches meet there
    c_node = c_inf + k.parallel_capacitance_f;
    row(i_vt) += -g1 - gd;
    row_b += g1;
    c_(i_vt) = 1.0;
  } else if (!cp) {  // v2 algebraic: v2 = a·v1 + b·vt
    const double gs = 1.0 / k.series_resistance_ohm, g = g1 + gs + gd;
    const double av = g1 / g, bv = gs / g;
    row(i_vt) += gs * (bv - 1.0);  // i_t = gs·(v2 − vt)
    row_b += gs * av;
    c_(i_vt) = bv;
    d_ = av;
  } else {  // both: v2 is a state on Cp
    const double gs = 1.0 / k.series_resistance_ohm, cpf = k.parallel_capacitance_f;
    a_(i_v2, i_v2) = (-g1 - gd - gs) / cpf;
    a_(i_v2, i_vt) = gs / cpf;
    b_(i_v2) = g1 / cpf;
    row(i_v2) += gs;
    row(i_vt) += -gs;
    c_(i_v2) = 1.0;
  }
  for (int j = 0; j < nd; ++j) {  // Debye branch j: C_j·u_j' = (vt − u_j)/R_j, R_j = τ_j/C_j
    const double cj = debye[j].first, tj = debye[j].second, gj = cj / tj;
    a_(i_d0 + j, i_vt) = 1.0 / tj;
    a_(i_d0 + j, i_d0 + j) = -1.0 / tj;
    row(i_vt) += -gj;
    row(i_d0 + j) += gj;
  }
  for (int m = 0; m < nm; ++m) {
    const Term& md = modes[m];
    const int ix = i_m0 + 2 * m, iy = ix + 1;
    const double ck = md.damping;
    a_(ix, iy) = 1.0;
    a_(iy, ix) = -md.omega * md.omega;
    a_(iy, iy) = -ck;
    a_(iy, i_vt) = md.participation;
    row(iy) += -md.participation;  // the modal current p·x' leaves the node
  }
  a_.row(i_vt) = row / c_node;
  b_(i_vt) = row_b / c_node;

  // Balance to energy coordinates (√C·v for capacitor voltages, ω·x and x' for
  // the modes): the raw matrix mixes ω² ~ 1e11 with p/C, and the matrix
  // exponential's accuracy is relative to the norm. x_s = T x.
  Eigen::VectorXd tdiag = Eigen::VectorXd::Ones(n);
  tdiag(i_vt) = std::sqrt(c_inf);
  if (v2_state) tdiag(i_v2) = std::sqrt(k.parallel_capacitance_f);
  for (int j = 0; j < nd; ++j) tdiag(i_d0 + j) = std::sqrt(debye[j].first);
  for (int m = 0; m < nm; ++m) tdiag(i_m0 + 2 * m) = modes[m].omega;
  for (int r = 0; r < n; ++r)
    for (int q = 0; q < n; ++q) a_(r, q) *= tdiag(r) / tdiag(q);
  b_ = b_.cwiseProduct(tdiag);
  c_ = c_.cwiseQuotient(tdiag.transpose());
}

const DividerStateSpace::Step& DividerStateSpace::step(double h) {
  const long long key = std::llround(h * 1e15);
  auto it = cache_.find(key);
  if (it != cache_.end()) return it->second;
  const int n = static_cast<int>(a_.rows());
  Eigen::MatrixXd aug = Eigen::MatrixXd::Zero(n + 2, n + 2);
  aug.topLeftCorner(n, n) = a_ * h;
  aug.block(0, n, n, 1) = b_ * h;
  aug(n, n + 1) = h;  // u' = m, scaled by h: the slope enters per unit time
  Eigen::MatrixXd e = aug.exp();
  Step s;
  s.phi = e.topLeftCorner(n, n);
  s.g0 = e.block(0, n, n, 1);
  s.g1 = e.block(0, n + 1, n, 1);
  return cache_.emplace(key, std::move(s)).first->second;
}

std::vector<double> DividerStateSpace::simulate(const drivers::sim::PiecewiseLinear& v1,
                                                std::span<const double> times) {
  if (v1.t.empty()) throw std::invalid_argument("DividerStateSpace::simulate: empty input");
  std::vector<double> out(times.size());
  Eigen::VectorXd x = Eigen::VectorXd::Zero(a_.rows());
  double t = v1.t.front();
  std::size_t j = 0;  // v1.t[j] is the first knot > t (segments between knots are linear)
  auto value_right = [&](double time) { return v1.at(time); };
  for (std::size_t k = 0; k < times.size(); ++k) {
    const double target = times[k];
    if (target < t - 1e-18) throw std::invalid_argument("DividerStateSpace::simulate: times not ascending");
    while (t < target) {
      while (j < v1.t.size() && v1.t[j] <= t) ++j;
      const double seg_end = j < v1.t.size() ? std::min(v1.t[j], target) : target;
      const double h = seg_end - t;
      if (h <= 0) break;
      const double u0 = value_right(t);
      double slope = 0.0;
      if (j < v1.t.size() && j > 0) {
        const double ta = v1.t[j - 1], tb = v1.t[j];
        if (tb > ta) slope = (v1.v[j] - v1.v[j - 1]) / (tb - ta);
      }
      const Step& s = step(h);
      x = s.phi * x + s.g0 * u0 + s.g1 * slope;
      t = seg_end;
    }
    out[k] = c_.dot(x) + d_ * v1.at(target);
  }
  return out;
}

std::complex<double> DividerStateSpace::transfer(double omega) const {
  const int n = static_cast<int>(a_.rows());
  if (n == 0) return d_;  // a purely resistive standard: no state
  Eigen::MatrixXcd m = std::complex<double>(0, omega) * Eigen::MatrixXcd::Identity(n, n) - a_.cast<std::complex<double>>();
  Eigen::VectorXcd xs = m.partialPivLu().solve(b_.cast<std::complex<double>>());
  return c_.cast<std::complex<double>>().dot(xs) + d_;
}

}  // namespace piezo::acq
