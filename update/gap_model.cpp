#include "update/gap_model.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "model/bench_response.hpp"

namespace piezo::update {

namespace {
constexpr double kMatUnit = 0.01;    // 1 % per x unit
constexpr double kDampUnit = 1e-3;   // damping ratio per x unit
constexpr double kLinStep = 0.1;     // x units (0.1 %) for the linearisation differences
constexpr int kMat = 4;
constexpr double kMassStep = 0.002;  // end-mass fraction step for its linearisation (0.1 x unit)
}  // namespace

struct GapModel::Linear {
  double xm[kMat] = {0, 0, 0, 0};  // material x of the linearisation point
  model::ModalPortModel base;
  struct Slope {
    double c0 = 0, cres = 0;
    std::vector<double> w, p2, kappa;
  };
  Slope d[kMat];  // per x unit
  // End-mass loading (effect mass_loading), when it is a fitted parameter:
  // the fraction at the linearisation point and the slope per unit fraction.
  double mass = 0;
  bool has_mass = false;
  Slope dm;
};

GapModel::GapModel(model::ModalSolver& solver, MaterialClass cls, TubeParams p_ref, model::RayleighDamping damping,
                   double r1_nominal_ohm, double damping_ref_hz, int n_modes)
    : solver_(&solver), cls_(std::move(cls)), p_ref_(p_ref), damping0_(damping), r1_(r1_nominal_ohm),
      w_ref_(2 * M_PI * damping_ref_hz), n_modes_(n_modes) {
  if (!(r1_ > 0) || !(w_ref_ > 0)) throw std::invalid_argument("GapModel: R1 and the damping reference must be > 0");
  set_effects({});
  relinearise(reference_x());
}

void GapModel::set_effects(const std::vector<std::string>& effects) {
  params_.clear();
  const double big = 50.0;  // ±50 % for the material: far outside any plausible update step
  params_.push_back({GapParam::y_e11, "YE11", nullptr, -big, big});
  // ν12 must stay below 0.5 (incompressible limit) for the isotropic stiffness to exist.
  params_.push_back({GapParam::nu12, "nu12", nullptr, -big, std::min(big, std::log(0.495 / p_ref_.nu12) / kMatUnit)});
  params_.push_back({GapParam::d31, "d31", nullptr, -big, big});
  params_.push_back({GapParam::eps_t33, "epsT33", nullptr, -big, big});
  params_.push_back({GapParam::damping_alpha, "rayleigh_alpha", nullptr, 0.0, 200.0});
  params_.push_back({GapParam::damping_beta, "rayleigh_beta", nullptr, 0.0, 200.0});
  for (const auto& name : effects) {
    const auto* e = model::find_effect(name);
    if (!e) throw std::invalid_argument("GapModel: unknown effect '" + name + "'");
    const auto [lo, hi] = model::effect_coordinate_bounds(*e);
    params_.push_back({GapParam::effect, name, e, lo, hi});
  }
  // The end mass is a direction of the linearised port: (un)set it with the
  // parameter, at the current linearisation point and no mass.
  const bool want_mass = std::find(effects.begin(), effects.end(), "mass_loading") != effects.end();
  if (lin_ && lin_->has_mass != want_mass) {
    std::vector<double> x = reference_x();
    for (int i = 0; i < kMat; ++i) x[static_cast<std::size_t>(i)] = lin_->xm[i];
    relinearise(x);
  }
}

std::vector<double> GapModel::reference_x() const {
  std::vector<double> x(params_.size(), 0.0);
  x[4] = damping0_.alpha / (2 * w_ref_) / kDampUnit;
  x[5] = damping0_.beta * w_ref_ / 2 / kDampUnit;
  for (std::size_t i = 6; i < params_.size(); ++i) {
    const auto& e = *params_[i].effect;
    const model::EffectSet neutral;
    x[i] = model::effect_coordinate(e, neutral.*(e.field));
  }
  return x;
}

TubeParams GapModel::material(const std::vector<double>& x) const {
  TubeParams p = p_ref_;
  p.y_e11 *= std::exp(kMatUnit * x[0]);
  p.nu12 *= std::exp(kMatUnit * x[1]);
  p.d31 *= std::exp(kMatUnit * x[2]);
  p.eps_t33 *= std::exp(kMatUnit * x[3]);
  return p;
}

model::RayleighDamping GapModel::damping(const std::vector<double>& x) const {
  return {2 * w_ref_ * kDampUnit * x[4], 2 / w_ref_ * kDampUnit * x[5]};
}

double GapModel::effect_value(const std::vector<double>& x, int i) const {
  return model::effect_from_coordinate(*params_.at(static_cast<std::size_t>(i)).effect, x[static_cast<std::size_t>(i)]);
}

model::EffectSet GapModel::effects(const std::vector<double>& x) const {
  model::EffectSet fx = fixed_;
  for (std::size_t i = 6; i < params_.size(); ++i) fx.*(params_[i].effect->field) = effect_value(x, static_cast<int>(i));
  return fx;
}

double GapModel::mass_of(const std::vector<double>& x) const { return effects(x).mass_loading; }

model::ModalPortModel GapModel::port_at(const TubeParams& p, double mass_fraction) const {
  model::ModalOptions mo;
  mo.n_modes = n_modes_;
  mo.end_mass_fraction = mass_fraction;
  auto port = solver_->port_model(cls_.e_form(p), mo);
  if (!port.converged) throw std::runtime_error("gap model: the FE modal solve did not converge");
  return port;
}

model::ModalPortModel GapModel::exact_port(const std::vector<double>& x) const {
  return port_at(material(x), mass_of(x));
}

double GapModel::relinearise(const std::vector<double>& x) {
  auto lin = std::make_shared<Linear>();
  double moved = 0;
  for (int i = 0; i < kMat; ++i) {
    lin->xm[i] = x[static_cast<std::size_t>(i)];
    if (lin_) moved = std::max(moved, std::fabs(x[static_cast<std::size_t>(i)] - lin_->xm[i]));
  }
  lin->mass = mass_of(x);
  lin->has_mass = std::any_of(params_.begin(), params_.end(), [](const GapParamInfo& p) {
    return p.effect && std::string(p.effect->name) == "mass_loading";
  });
  lin->base = port_at(material(x), lin->mass);
  const std::size_t nm = lin->base.modes.size();
  auto slope = [&](const model::ModalPortModel& pp, double step, Linear::Slope& s) {
    if (pp.modes.size() != nm) throw std::runtime_error("gap model: mode count changed under a linearisation step");
    s.c0 = (pp.c_clamped - lin->base.c_clamped) / step;
    s.cres = (pp.c_residual - lin->base.c_residual) / step;
    s.w.resize(nm);
    s.p2.resize(nm);
    s.kappa.resize(nm);
    for (std::size_t k = 0; k < nm; ++k) {
      const auto &a = lin->base.modes[k], &b = pp.modes[k];
      s.w[k] = (b.omega - a.omega) / step;
      s.p2[k] = (b.participation * b.participation - a.participation * a.participation) / step;
      s.kappa[k] = (b.kappa - a.kappa) / step;
    }
  };
  for (int i = 0; i < kMat; ++i) {
    std::vector<double> xp = x;
    xp[static_cast<std::size_t>(i)] += kLinStep;
    slope(port_at(material(xp), lin->mass), kLinStep, lin->d[i]);
  }
  // The mass direction per unit fraction: central where the fraction allows
  // (it is >= 0), else forward — the modes move with the mass far from
  // linearly, and a one-sided slope biases the fitted fraction by several %.
  if (lin->has_mass) {
    if (lin->mass >= kMassStep) {
      Linear::Slope up, down;
      slope(port_at(material(x), lin->mass + kMassStep), kMassStep, up);
      slope(port_at(material(x), lin->mass - kMassStep), -kMassStep, down);
      lin->dm = up;
      lin->dm.c0 = 0.5 * (up.c0 + down.c0);
      lin->dm.cres = 0.5 * (up.cres + down.cres);
      for (std::size_t k = 0; k < nm; ++k) {
        lin->dm.w[k] = 0.5 * (up.w[k] + down.w[k]);
        lin->dm.p2[k] = 0.5 * (up.p2[k] + down.p2[k]);
        lin->dm.kappa[k] = 0.5 * (up.kappa[k] + down.kappa[k]);
      }
    } else {
      slope(port_at(material(x), lin->mass + kMassStep), kMassStep, lin->dm);
    }
  }
  lin_ = std::move(lin);
  return moved;
}

double GapModel::distance_from_linearisation(const std::vector<double>& x) const {
  double d = 0;
  for (int i = 0; i < kMat; ++i) d = std::max(d, std::fabs(x[static_cast<std::size_t>(i)] - lin_->xm[i]));
  // The mass in the same currency: 0.01 of fraction ≈ 1 % of the modal mass.
  if (lin_->has_mass) d = std::max(d, std::fabs(mass_of(x) - lin_->mass) / kMatUnit);
  return d;
}

std::vector<std::complex<double>> GapModel::impedance(const std::vector<double>& x,
                                                      const std::vector<double>& f_hz) const {
  // First-order Taylor of C0, C_res and per mode ω_k, p_k², κ_k (p_k's sign is arbitrary).
  model::ModalPortModel p = lin_->base;
  const double dmass = lin_->has_mass ? mass_of(x) - lin_->mass : 0.0;
  for (std::size_t k = 0; k < p.modes.size(); ++k) {
    double w = p.modes[k].omega, p2 = p.modes[k].participation * p.modes[k].participation, kap = p.modes[k].kappa;
    for (int i = 0; i < kMat; ++i) {
      const double dx = x[static_cast<std::size_t>(i)] - lin_->xm[i];
      w += lin_->d[i].w[k] * dx;
      p2 += lin_->d[i].p2[k] * dx;
      kap += lin_->d[i].kappa[k] * dx;
    }
    if (dmass != 0.0) {
      w += lin_->dm.w[k] * dmass;
      p2 += lin_->dm.p2[k] * dmass;
      kap += lin_->dm.kappa[k] * dmass;
    }
    p.modes[k].omega = w;
    p.modes[k].participation = std::sqrt(std::max(0.0, p2));
    p.modes[k].kappa = kap;
  }
  for (int i = 0; i < kMat; ++i) {
    const double dx = x[static_cast<std::size_t>(i)] - lin_->xm[i];
    p.c_clamped += lin_->d[i].c0 * dx;
    p.c_residual += lin_->d[i].cres * dx;
  }
  p.c_clamped += lin_->dm.c0 * dmass;
  p.c_residual += lin_->dm.cres * dmass;
  return model::bench_impedance(p, damping(x), effects(x), r1_, f_hz);
}

}  // namespace piezo::update
