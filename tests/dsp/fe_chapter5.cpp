#include "fe_chapter5.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "dsp/features.hpp"
#include "model/material_spec.hpp"
#include "model/modal.hpp"
#include "model/transient.hpp"
#include "model/tube_model.hpp"

namespace piezo::fe5 {

namespace {
using cd = std::complex<double>;

// The divider with the tube's port as a modal circuit (model/port_model.hpp):
//   Ce v̇ = (v1 − v)/R1 − Σ i_k,  q̇_k = i_k,  i̇_k = p_k² v − ω_k² q_k − c_k i_k,
// Ce = C0 + C_res, c_k = α + β κ_k, v2 = v. Energy-scaled states (√Ce·v,
// ω_k q_k/p_k, i_k/p_k) keep the eigenproblem well conditioned. For
// v1 = A·e^{−a t} from rest, x(t) = Σ_k w_k (W⁻¹b)_k A (e^{λ_k t} − e^{−a t})/(λ_k + a).
bvd::DividerResponse pole_residue(const model::ModalPortModel& port,
                                  const model::RayleighDamping& d, double r1, double amp,
                                  double a) {
  std::vector<model::PortMode> modes;  // modes that couple to the electrode
  for (const auto& m : port.modes)
    if (m.omega > 0 &&
        m.participation * m.participation / (m.omega * m.omega) > 1e-12 * port.c_static)
      modes.push_back(m);
  const double ce = port.c_clamped + port.c_residual;
  const auto n = static_cast<Eigen::Index>(1 + 2 * modes.size());
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(n), scale = Eigen::VectorXd::Ones(n);
  A(0, 0) = -1.0 / (r1 * ce);
  b[0] = 1.0 / (r1 * ce);
  scale[0] = std::sqrt(ce);
  for (std::size_t k = 0; k < modes.size(); ++k) {
    const auto& m = modes[k];
    const auto q = static_cast<Eigen::Index>(1 + 2 * k), i = q + 1;
    A(0, i) = -1.0 / ce;
    A(q, i) = 1.0;
    A(i, 0) = m.participation * m.participation;
    A(i, q) = -m.omega * m.omega;
    A(i, i) = -(d.alpha + d.beta * m.kappa);
    scale[q] = m.omega / std::abs(m.participation);
    scale[i] = 1.0 / std::abs(m.participation);
  }
  const Eigen::MatrixXd As = scale.asDiagonal() * A * scale.cwiseInverse().asDiagonal();
  const Eigen::VectorXd bs = scale.cwiseProduct(b);
  Eigen::ComplexEigenSolver<Eigen::MatrixXcd> es(As.cast<cd>());
  const Eigen::MatrixXcd W = es.eigenvectors();
  const Eigen::VectorXcd wb = W.partialPivLu().solve(bs.cast<cd>());
  bvd::DividerResponse out;
  out.v1.lambda = {cd(-a, 0)};
  out.v1.residue = {cd(amp, 0)};
  cd r_input = 0;
  for (Eigen::Index k = 0; k < n; ++k) {
    const cd lam = es.eigenvalues()[k];
    const cd r = W(0, k) / scale[0] * wb[k] * amp / (lam + a);
    out.v2.lambda.push_back(lam);
    out.v2.residue.push_back(r);
    out.circuit_poles.push_back(lam);
    r_input -= r;
  }
  out.v2.lambda.push_back(cd(-a, 0));
  out.v2.residue.push_back(r_input);
  out.i.lambda = out.v2.lambda;
  for (const cd& r : out.v2.residue) out.i.residue.push_back(-r / r1);
  out.i.residue.back() += amp / r1;
  return out;
}

FeChapter5 build() {
  FeChapter5 fe;
  const auto mat = model::resolve_material({"apc850", false, ""});
  model::TubeGeometry g;  // the published tube
  g.density_kg_m3 = mat.density_kg_m3;
  model::TubeModel tube(g);
  model::ModalSolver solver(tube);
  model::ModalOptions mo;
  mo.n_modes = 24;  // as the simulated bench (acq::SimSpec::modes)
  fe.port = solver.port_model(model::to_e_form(mat.d), mo);
  std::vector<double> u(fe.record);
  for (std::size_t k = 0; k < fe.record; ++k)
    u[k] = fe.amplitude_v * std::exp(-fe.decay_per_s * double(k) / fe.sample_rate_hz);
  model::DividerCircuit circuit;
  circuit.r1_ohm = fe.r1_ohm;
  fe.v1 = u;
  fe.v2 = model::simulate_divider(fe.port, fe.damping, circuit, u, fe.sample_rate_hz);
  fe.exact = pole_residue(fe.port, fe.damping, fe.r1_ohm, fe.amplitude_v, fe.decay_per_s);
  return fe;
}
}  // namespace

std::complex<double> FeChapter5::z(double f_hz) const {
  const double w = 2.0 * std::numbers::pi * f_hz;
  return 1.0 / (cd(0.0, w) * port.charge_per_volt(w, damping));
}

const FeChapter5& chapter5() {
  static const FeChapter5 fe = build();
  return fe;
}

std::pair<double, double> noise_std(const FeChapter5& fe, double level) {
  return {level * bvd::std_dev(fe.v1), level * bvd::std_dev(fe.v2)};
}

study::StudyInput study_input(const FeChapter5& fe, double level, std::uint64_t seed,
                              std::size_t records) {
  study::StudyInput in;
  in.sample_rate_hz = fe.sample_rate_hz;
  in.r1_ohm = fe.r1_ohm;
  for (std::size_t r = 0; r < records; ++r) {
    in.v1.push_back(bvd::add_noise(fe.v1, level, seed * 1000 + 2 * r));
    in.v2.push_back(bvd::add_noise(fe.v2, level, seed * 1000 + 2 * r + 1));
  }
  in.z_true = [&fe](double f) { return fe.z(f); };
  const auto truth = dsp::find_features(in.z_true, in.f_lo_hz, in.f_hi_hz, 10.0);
  for (const auto& f : truth.resonances) in.true_resonances_hz.push_back(f.f_hz);
  for (const auto& f : truth.antiresonances) in.true_antiresonances_hz.push_back(f.f_hz);
  return in;
}

CrbModel crb_model(const bvd::DividerResponse& r, double sigma_v1, double sigma_v2) {
  CrbModel m;
  crb::Channel c1{{}, sigma_v1}, c2{{}, sigma_v2};
  for (std::size_t i = 0; i < r.v2.lambda.size(); ++i) {
    cd l = r.v2.lambda[i], res = r.v2.residue[i];
    if (std::abs(l.imag()) <= 1e-9 * std::abs(l)) {  // real (eigen-solver round-off in Im)
      l = l.real();
      res = res.real();
    } else if (l.imag() < 0) {
      continue;  // the conjugate of a pair member kept
    }
    m.poles.push_back(l);
    c2.residue.push_back(res);
    // v1 holds the drive pole only.
    c1.residue.push_back(r.v1.lambda.size() == 1 && l == r.v1.lambda[0] ? r.v1.residue[0] : cd(0));
  }
  m.channels = {c1, c2};
  return m;
}

std::vector<bool> known_except_dominant(const CrbModel& m, double f_max_hz, std::size_t pairs) {
  const double w_max = 2.0 * std::numbers::pi * f_max_hz;
  std::vector<bool> known(m.poles.size(), true);
  std::vector<std::size_t> osc;
  for (std::size_t i = 0; i < m.poles.size(); ++i) {
    if (std::abs(m.poles[i]) > w_max) continue;
    if (m.poles[i].imag() == 0)
      known[i] = false;
    else
      osc.push_back(i);
  }
  const auto& r = m.channels[1].residue;
  std::sort(osc.begin(), osc.end(),
            [&](std::size_t a, std::size_t b) { return std::abs(r[a]) > std::abs(r[b]); });
  for (std::size_t k = 0; k < std::min(pairs, osc.size()); ++k) known[osc[k]] = false;
  return known;
}

namespace {
CrbModel crb_at(const FeChapter5& fe, double level, CrbClass cls, std::vector<bool>& known) {
  const auto [s1, s2] = noise_std(fe, level);
  CrbModel m = crb_model(fe.exact, s1, s2);
  known = cls == CrbClass::Reduced ? known_except_dominant(m, 130e3, 3) : std::vector<bool>{};
  return m;
}
}  // namespace

FeatureBounds feature_crb(const FeChapter5& fe, const study::StudyInput& in, double level,
                          std::size_t n, CrbClass cls) {
  std::vector<bool> known;
  const CrbModel m = crb_at(fe, level, cls, known);
  std::vector<double> f = in.true_resonances_hz;
  f.insert(f.end(), in.true_antiresonances_hz.begin(), in.true_antiresonances_hz.end());
  const auto c = crb::divider_feature_crb(m.poles, m.channels, fe.sample_rate_hz, n, f, known);
  FeatureBounds b;
  for (std::size_t k = 0; k < c.size(); ++k)
    (k < in.true_resonances_hz.size() ? b.res_rel : b.anti_rel)
        .push_back(c[k].sigma_hz / c[k].f_hz);
  return b;
}

std::vector<double> db_crb(const FeChapter5& fe, double level, std::size_t n,
                           const std::vector<double>& f_hz, CrbClass cls) {
  std::vector<bool> known;
  const CrbModel m = crb_at(fe, level, cls, known);
  return crb::divider_db_crb(m.poles, m.channels, fe.sample_rate_hz, n, f_hz, known);
}

}  // namespace piezo::fe5
