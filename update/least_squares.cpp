#include "update/least_squares.hpp"

#include <Eigen/Cholesky>
#include <chrono>
#include <cmath>
#include <optional>
#include <stdexcept>

#include "numerics/levenberg_marquardt.hpp"
#include "update/condensed_stiffness.hpp"
#include "update/updater.hpp"

namespace piezo::update {

namespace {

constexpr int kNp = 4;

struct Evaluation {
  Eigen::VectorXd r;  // weighted residuals
  Eigen::MatrixXd j;  // weighted Jacobian (filled on demand)
  std::vector<double> f_sc, f_oc;
  double cost = 0;
};

class Problem {
 public:
  Problem(const model::TubeModel& tube, model::ModalSolver& solver, const MaterialClass& cls,
          const TubeParams& p0, const MeasuredFeatures& mf, const LmOptions& opt)
      : tube_(tube), solver_(solver), cls_(cls), p0_(p0), mf_(mf), opt_(opt) {
    nr_ = static_cast<int>(mf.resonances_hz.size());
    na_ = static_cast<int>(mf.antiresonances_hz.size());
    c_meas_ = mf.low_frequency_capacitance();
    w_.resize(nr_ + na_ + 1);
    for (int j = 0; j < nr_; ++j)
      w_[j] = mf.resonance_sigma_hz.empty() ? 1.0 : mf.resonances_hz[j] / mf.resonance_sigma_hz[j];
    for (int j = 0; j < na_; ++j)
      w_[nr_ + j] = mf.antiresonance_sigma_hz.empty()
                        ? 1.0
                        : mf.antiresonances_hz[j] / mf.antiresonance_sigma_hz[j];
    w_[nr_ + na_] = mf.low_z_sigma_ohm > 0 ? mf.low_z_ohm / mf.low_z_sigma_ohm : 1.0;
  }

  TubeParams params(const Eigen::Vector4d& x) const {
    TubeParams p = p0_;
    p.y_e11 = p0_.y_e11 * std::exp(x[0]);
    p.nu12 = p0_.nu12 * std::exp(x[1]);
    p.d31 = p0_.d31 * std::exp(x[2]);
    p.eps_t33 = p0_.eps_t33 * std::exp(x[3]);
    return p;
  }

  // Residuals (and the Jacobian when `jac`); nullopt + message when the model fails.
  std::optional<Evaluation> evaluate(const Eigen::Vector4d& x, bool jac, std::string& why) {
    ++evaluations;
    model::PiezoMaterialE mat;
    try {
      mat = cls_.e_form(params(x));
    } catch (const std::invalid_argument& e) {
      why = e.what();
      return std::nullopt;
    }
    Evaluation ev;
    ev.r.resize(nr_ + na_ + 1);
    ev.j.setZero(nr_ + na_ + 1, kNp);
    std::vector<model::MaterialWeights> dw;
    if (jac)
      for (int k = 0; k < kNp; ++k) {
        auto mat_k = [&](double xk) {
          Eigen::Vector4d y = x;
          y[k] = xk;
          return cls_.e_form(params(y));
        };
        try {
          dw.push_back(weight_tangent(mat_k, x[k], 1e-6));
        } catch (const std::invalid_argument& e) {
          why = e.what();
          return std::nullopt;
        }
      }
    double dyn = 0;  // ω² term of the capacitance at f_L
    auto modes = [&](model::Electrodes el, const std::vector<double>& meas, int row0,
                     std::vector<double>& out) -> bool {
      const auto res = solver_.solve(mat, el, opt_.modal);
      if (!res.converged) {
        why = "modal solve failed: " + res.message;
        return false;
      }
      std::vector<int> act;
      for (std::size_t k = 0; k < res.modes.size(); ++k)
        if (res.modes[k].electrically_active) act.push_back(static_cast<int>(k));
      if (act.size() < meas.size()) {
        why = "fewer electrically active modes than measured frequencies";
        return false;
      }
      if (el == model::Electrodes::short_circuit)
        for (const auto& m : res.modes)  // not the rigid mode (see model_capacitance)
          if (m.omega > 2.0 * M_PI * 1e-3 * opt_.modal.shift_hz)
            dyn += m.participation * m.participation / (m.eigenvalue * m.eigenvalue);
      const int n = static_cast<int>(meas.size());
      Eigen::MatrixXd phi(tube_.n_u(), n);
      for (int j = 0; j < n; ++j) {
        const auto& m = res.modes[act[j]];
        out.push_back(m.frequency_hz);
        ev.r[row0 + j] = w_[row0 + j] * (m.frequency_hz / meas[j] - 1.0);
        phi.col(j) = res.shapes.col(act[j]);
      }
      if (jac) {
        const CondensedStiffness ks(tube_, mat, el);
        for (int k = 0; k < kNp; ++k) {
          const Eigen::MatrixXd dl = ks.dbilinear(dw[k], phi, phi);  // Hellmann–Feynman
          for (int j = 0; j < n; ++j) {
            const double omega = res.modes[act[j]].omega;
            ev.j(row0 + j, k) = w_[row0 + j] * dl(j, j) / (4.0 * M_PI * omega) / meas[j];
          }
        }
      }
      return true;
    };
    if (!modes(model::Electrodes::short_circuit, mf_.resonances_hz, 0, ev.f_sc))
      return std::nullopt;
    if (!modes(model::Electrodes::open_circuit, mf_.antiresonances_hz, nr_, ev.f_oc))
      return std::nullopt;
    const double w2 = std::pow(2.0 * M_PI * mf_.low_z_hz, 2);
    const double c_static = solver_.static_capacitance(mat);
    const int rc = nr_ + na_;
    ev.r[rc] = w_[rc] * ((c_static + w2 * dyn) / c_meas_ - 1.0);
    if (jac)
      for (int k = 0; k < kNp; ++k) {
        Eigen::Vector4d y = x;
        const double h = 1e-6;
        y[k] += h;
        double cs = 0;
        try {
          cs = solver_.static_capacitance(cls_.e_form(params(y)));
        } catch (const std::invalid_argument& e) {
          why = e.what();
          return std::nullopt;
        }
        ev.j(rc, k) = w_[rc] * (cs - c_static) / h / c_meas_;
      }
    ev.cost = 0.5 * ev.r.squaredNorm();
    return ev;
  }

  int evaluations = 0;

 private:
  const model::TubeModel& tube_;
  model::ModalSolver& solver_;
  const MaterialClass& cls_;
  TubeParams p0_;
  const MeasuredFeatures& mf_;
  const LmOptions& opt_;
  int nr_ = 0, na_ = 0;
  double c_meas_ = 0;
  std::vector<double> w_;
};

}  // namespace

LmResult update_lm(const model::TubeModel& tube, model::ModalSolver& solver,
                   const MaterialClass& cls, const TubeParams& original,
                   const MeasuredFeatures& features, const LmOptions& opt) {
  const auto t0 = std::chrono::steady_clock::now();
  features.validate();
  if (!(original.d31 != 0) || !(original.nu12 > 0))
    throw std::invalid_argument("update_lm: the original d31 must be non-zero and nu12 > 0");
  if (features.resonances_hz.size() + features.antiresonances_hz.size() + 1 < kNp)
    throw std::invalid_argument("update_lm: fewer measured quantities than the 4 parameters");
  LmResult res;
  Problem prob(tube, solver, cls, original, features, opt);
  auto done = [&](UpdateStatus st, std::string msg) {
    res.status = st;
    res.message = std::move(msg);
    res.evaluations = prob.evaluations;
    res.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return res;
  };
  // The engine asks for r at trials and then for J at the accepted one; one
  // evaluation gives both (Hellmann–Feynman), so the last ones are kept.
  std::vector<std::pair<Eigen::VectorXd, Evaluation>> evaluated;
  std::string why_start;
  auto evaluation = [&](const Eigen::VectorXd& x, std::string& why) -> const Evaluation* {
    for (const auto& [xe, ev] : evaluated)
      if (xe == x) return &ev;
    auto ev = prob.evaluate(Eigen::Vector4d(x), true, why);
    if (!ev) return nullptr;
    if (evaluated.size() >= 2) evaluated.erase(evaluated.begin());
    evaluated.emplace_back(x, std::move(*ev));
    return &evaluated.back().second;
  };
  numerics::LmProblem pb;
  bool first = true;
  pb.residual = [&](const Eigen::VectorXd& x) -> std::optional<Eigen::VectorXd> {
    std::string w;
    const Evaluation* ev = evaluation(x, first ? why_start : w);
    first = false;
    if (!ev) return std::nullopt;
    return ev->r;
  };
  pb.jacobian = [&](const Eigen::VectorXd& x, const Eigen::VectorXd&, Eigen::MatrixXd& j,
                    const numerics::LmJacobianCall&) {
    std::string w;
    const Evaluation* ev = evaluation(x, w);
    if (!ev) return false;
    j = ev->j;
    return true;
  };
  numerics::LmSettings ls;  // this updater's damping before the shared engine
  ls.max_iterations = opt.max_iterations;
  ls.max_tries = 12;
  ls.mu0 = opt.lambda0;
  ls.diag_floor = 1e-30;
  ls.step_tolerance = opt.step_tolerance;
  ls.on_stall = numerics::LmSettings::Stall::failed;
  const numerics::LmRun run = numerics::levenberg_marquardt(pb, Eigen::VectorXd::Zero(kNp), ls);
  if (run.stop == numerics::LmRun::Stop::bad_start)
    return done(UpdateStatus::non_physical, "original model: " + why_start);
  res.iterations = run.iterations;
  std::string w;
  const Evaluation* cur = evaluation(run.x, w);
  res.updated = prob.params(Eigen::Vector4d(run.x));
  res.cost = run.cost;
  res.residuals.assign(run.r.data(), run.r.data() + run.r.size());
  if (cur) {
    res.model_resonances_hz = cur->f_sc;
    res.model_antiresonances_hz = cur->f_oc;
  }
  if (!run.converged)
    return done(UpdateStatus::max_iterations, "Levenberg-Marquardt did not converge in " +
                                                  std::to_string(opt.max_iterations) +
                                                  " iterations");
  return done(UpdateStatus::converged, "");
}

}  // namespace piezo::update
