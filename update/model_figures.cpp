#include "update/model_figures.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <stdexcept>

#include "update/output_error/forward_model.hpp"

namespace piezo::update {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

struct PortCircuit {
  dsp::EquivalentCircuit circuit;
  std::vector<bool> residual;  // per branch: the residual pseudo-mode (never reported)
  double c_static = 0;
};

PortCircuit circuit_of(const model::ModalPortModel& port, const OeLoss& loss, double active_coupling) {
  PortCircuit pc;
  auto& c = pc.circuit;
  c.c0_f = port.c_clamped + port.c_residual;
  c.tan_delta = 0;
  c.rs_ohm = 0;
  pc.c_static = port.c_static;
  std::vector<std::pair<dsp::CircuitBranch, bool>> br;
  for (const auto& m : port.modes) {
    if (!(m.omega > 0) || m.participation == 0) continue;
    const double p2 = m.participation * m.participation, w2 = m.omega * m.omega;
    const double coupling = p2 / (w2 * port.c_clamped);
    if (!m.residual && !(m.symmetric && coupling >= active_coupling)) {
      c.c0_f += p2 / w2;  // an inactive mode: its static share only
      continue;
    }
    dsp::CircuitBranch b;
    b.l_h = 1.0 / p2;
    b.c_f = p2 / w2;
    const double damping = loss.model == OeDamping::rayleigh ? loss.beta_s * m.kappa   // c_k = βκ_k (α = 0)
                                                             : loss.eta * m.kappa / m.omega;  // ηκ_k/ω_k at resonance
    b.r_ohm = std::max(damping, 1e-300) / p2;
    br.push_back({b, m.residual});
  }
  std::sort(br.begin(), br.end(), [](const auto& a, const auto& b) { return a.first.fs_hz() < b.first.fs_hz(); });
  for (const auto& [b, r] : br) {
    c.branches.push_back(b);
    pc.residual.push_back(r);
  }
  return pc;
}

}  // namespace

dsp::EquivalentCircuit port_circuit(const model::ModalPortModel& port, const OeLoss& loss, double active_coupling) {
  return circuit_of(port, loss, active_coupling).circuit;
}

ModelFigures model_figures(model::ModalSolver& solver, const MaterialClass& cls, const TubeParams& params,
                           const OeLoss& loss, const Eigen::MatrixXd& covariance_rel, double band_lo_hz,
                           double band_hi_hz, const model::ModalOptions& modal, const model::EffectSet& effects) {
  model::ModalOptions mo = modal;
  mo.end_mass_fraction = effects.mass_loading;
  ModelFigures out;
  // θ in the output-error fit's relative coordinates about the answer.
  const oe::Coordinates5 co{params, loss.model == OeDamping::rayleigh ? loss.beta_s : loss.eta, loss.model};
  auto build = [&](const Eigen::VectorXd& x) {
    const auto port = solver.port_model(cls.e_form(co.params(x)), mo);
    ++out.port_models;
    if (!port.converged) throw std::runtime_error("the FE modal solve did not converge for the updated constants");
    return circuit_of(port, {loss.model, co.beta(x), co.eta(x)}, mo.active_coupling);
  };
  const Eigen::VectorXd x0 = Eigen::VectorXd::Zero(5);
  const PortCircuit centre = build(x0);
  out.circuit = centre.circuit;
  out.c0_f.value = centre.circuit.c0_f;
  out.free_capacitance_f.value = centre.c_static;
  out.tan_delta = {0.0, 0.0};
  std::vector<std::size_t> reported;  // branch indices of the reported modes
  for (std::size_t k = 0; k < centre.circuit.branches.size(); ++k) {
    const double fs = centre.circuit.branches[k].fs_hz();
    if (centre.residual[k] || fs < band_lo_hz || fs > band_hi_hz) continue;
    reported.push_back(k);
    out.modes.push_back(dsp::circuit_mode_figures(centre.circuit, k));
  }
  if (reported.empty())
    out.notes.push_back("the model has no electrically active mode between " + std::to_string(band_lo_hz) +
                        " and " + std::to_string(band_hi_hz) + " Hz");
  if (covariance_rel.rows() != 5 || covariance_rel.cols() != 5) {
    out.notes.push_back("no covariance of the constants: the figures carry no sigma");
    return out;
  }
  // σ along the covariance's principal axes (central differences at ±1σ).
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(0.5 * (covariance_rel + covariance_rel.transpose()));
  std::vector<std::vector<double>> var(out.modes.size());
  for (std::size_t i = 0; i < out.modes.size(); ++i) var[i].assign(dsp::named_figures(out.modes[i]).size(), 0.0);
  double var_c0 = 0, var_ct = 0;
  for (Eigen::Index j = 0; j < 5; ++j) {
    const double lambda = es.eigenvalues()[j];
    if (!(lambda > 0)) continue;
    const Eigen::VectorXd d = std::sqrt(lambda) * es.eigenvectors().col(j);
    const PortCircuit plus = build(d), minus = build(-d);
    var_c0 += std::pow(0.5 * (plus.circuit.c0_f - minus.circuit.c0_f), 2);
    var_ct += std::pow(0.5 * (plus.c_static - minus.c_static), 2);
    for (std::size_t i = 0; i < out.modes.size(); ++i) {
      const double fs = out.modes[i].fs_hz.value;
      // The same mode in the perturbed models: the nearest reportable branch in fs.
      auto same = [&](const PortCircuit& pc) -> std::optional<dsp::CircuitModeFigures> {
        std::optional<std::size_t> best;
        for (std::size_t k = 0; k < pc.circuit.branches.size(); ++k) {
          if (pc.residual[k]) continue;
          const double e = std::abs(pc.circuit.branches[k].fs_hz() / fs - 1);
          if (!best || e < std::abs(pc.circuit.branches[*best].fs_hz() / fs - 1)) best = k;
        }
        if (!best || std::abs(pc.circuit.branches[*best].fs_hz() / fs - 1) > 0.05) return std::nullopt;
        return dsp::circuit_mode_figures(pc.circuit, *best);
      };
      const auto gp = same(plus), gm = same(minus);
      const auto names = dsp::named_figures(out.modes[i]);
      for (std::size_t q = 0; q < names.size(); ++q) {
        const double a = gp ? dsp::named_figures(*gp)[q].second->value : dsp::kNaN;
        const double b = gm ? dsp::named_figures(*gm)[q].second->value : dsp::kNaN;
        var[i][q] += std::isfinite(a) && std::isfinite(b) ? std::pow(0.5 * (a - b), 2) : dsp::kNaN;
      }
    }
  }
  for (std::size_t i = 0; i < out.modes.size(); ++i) {
    const auto names = dsp::named_figures(out.modes[i]);
    for (std::size_t q = 0; q < names.size(); ++q)
      if (std::isfinite(names[q].second->value)) names[q].second->sigma = std::sqrt(var[i][q]);
  }
  out.c0_f.sigma = std::sqrt(var_c0);
  out.free_capacitance_f.sigma = std::sqrt(var_ct);
  return out;
}

Eigen::MatrixXd total_covariance_rel(const OeResult& r) {
  const Eigen::MatrixXd& c = r.covariance_rel;
  if (c.rows() != 5 || c.cols() != 5 || r.parameters.size() < 5) return {};
  Eigen::VectorXd s = Eigen::VectorXd::Ones(5);
  for (Eigen::Index i = 0; i < 5; ++i) {
    const auto& p = r.parameters[static_cast<std::size_t>(i)];
    const double stat_rel = std::sqrt(std::max(0.0, c(i, i)));
    // Relative total sigma of each coordinate: σ/|value| (nu12's coordinate is
    // nu12/nu12₀ − 1 about the answer, the others logs).
    const double total_rel = p.value != 0 ? p.sigma / std::abs(p.value) : dsp::kNaN;
    if (stat_rel > 0 && std::isfinite(total_rel) && total_rel > stat_rel) s[i] = total_rel / stat_rel;
  }
  return s.asDiagonal() * c * s.asDiagonal();
}

}  // namespace piezo::update
