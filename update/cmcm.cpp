#include "update/cmcm.hpp"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "update/condensed_stiffness.hpp"

namespace piezo::update {

const char* to_string(UpdateStatus s) {
  switch (s) {
    case UpdateStatus::converged:
      return "converged";
    case UpdateStatus::max_iterations:
      return "max_iterations";
    case UpdateStatus::ambiguous_pairing:
      return "ambiguous_pairing";
    case UpdateStatus::too_few_modes:
      return "too_few_modes";
    case UpdateStatus::non_physical:
      return "non_physical";
    case UpdateStatus::solver_failure:
      return "solver_failure";
    default:
      return "bad_input";
  }
}

TsvdSolution solve_tsvd(const Eigen::MatrixXd& g, const Eigen::VectorXd& f, double rel_tol) {
  if (g.rows() != f.size() || g.cols() == 0)
    throw std::invalid_argument("solve_tsvd: G and f sizes do not match");
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(g, Eigen::ComputeThinU | Eigen::ComputeThinV);
  TsvdSolution s;
  s.singular_values = svd.singularValues();
  s.x = Eigen::VectorXd::Zero(g.cols());
  if (s.singular_values.size() == 0 || !(s.singular_values[0] > 0)) return s;
  const double cut = rel_tol * s.singular_values[0];
  const Eigen::VectorXd utf = svd.matrixU().transpose() * f;
  for (Eigen::Index p = 0; p < s.singular_values.size(); ++p) {
    if (!(s.singular_values[p] > cut)) break;                       // sorted decreasingly (eq. 192)
    s.x += svd.matrixV().col(p) * (utf[p] / s.singular_values[p]);  // eq. 193
    ++s.rank;
  }
  return s;
}

CmcmEquations cmcm_equations(const Eigen::MatrixXd& k, const std::vector<Eigen::MatrixXd>& k_n,
                             const Eigen::MatrixXd& m, const std::vector<Eigen::MatrixXd>& m_n,
                             const Eigen::MatrixXd& phi, const Eigen::VectorXd& lambda,
                             const Eigen::MatrixXd& phi_star, const Eigen::VectorXd& lambda_star,
                             double min_cross) {
  if (phi.cols() != lambda.size() || phi_star.cols() != lambda_star.size() ||
      phi.rows() != k.rows() || phi_star.rows() != k.rows())
    throw std::invalid_argument("cmcm_equations: inconsistent sizes");
  const int ne = static_cast<int>(k_n.size()), nb = static_cast<int>(m_n.size());
  const Eigen::MatrixXd kx = phi.transpose() * k * phi_star;  // Φ_iᵀKΦ*_j
  const Eigen::MatrixXd mx = phi.transpose() * m * phi_star;
  std::vector<Eigen::MatrixXd> an, bn;
  for (const auto& kn : k_n) an.push_back(phi.transpose() * kn * phi_star);
  for (const auto& mn : m_n) bn.push_back(phi.transpose() * mn * phi_star);
  CmcmEquations eq;
  std::vector<Eigen::VectorXd> rows;
  std::vector<double> rhs;
  for (int i = 0; i < phi.cols(); ++i)
    for (int j = 0; j < phi_star.cols(); ++j) {
      const double ni = std::sqrt(phi.col(i).dot(m * phi.col(i)));
      const double nj = std::sqrt(phi_star.col(j).dot(m * phi_star.col(j)));
      if (std::abs(mx(i, j)) < min_cross * ni * nj) continue;
      const double b = lambda_star[j] / lambda[i];  // eq. 185
      Eigen::VectorXd row(ne + nb);
      for (int n = 0; n < ne; ++n) row[n] = an[n](i, j) / kx(i, j);            // eq. 182
      for (int n = 0; n < nb; ++n) row[ne + n] = -b * bn[n](i, j) / mx(i, j);  // eqs 183, 187
      rows.push_back(row);
      rhs.push_back(b - 1.0);
      eq.pairs.emplace_back(i, j);
    }
  eq.g.resize(static_cast<Eigen::Index>(rows.size()), ne + nb);
  eq.f.resize(static_cast<Eigen::Index>(rows.size()));
  for (std::size_t r = 0; r < rows.size(); ++r) {
    eq.g.row(static_cast<Eigen::Index>(r)) = rows[r].transpose();
    eq.f[static_cast<Eigen::Index>(r)] = rhs[r];
  }
  return eq;
}

namespace {

std::vector<int> active_modes(const model::ModalResult& r) {
  std::vector<int> idx;
  for (std::size_t k = 0; k < r.modes.size(); ++k)
    if (r.modes[k].electrically_active) idx.push_back(static_cast<int>(k));
  return idx;
}

std::string hz_list(const std::vector<double>& v) {
  std::ostringstream s;
  s.precision(6);
  for (std::size_t i = 0; i < v.size(); ++i) s << (i ? ", " : "") << v[i];
  return s.str();
}

}  // namespace

CmcmResult extended_cmcm(const model::TubeModel& tube, model::ModalSolver& solver,
                         const CmcmPhase& phase, const CmcmOptions& opt) {
  CmcmResult res;
  const int nt = static_cast<int>(phase.theta0.size());
  const int nj = static_cast<int>(phase.measured_hz.size());
  if (nt == 0 || nj == 0 || !phase.material) {
    res.message = phase.name + ": no coordinates, no measured frequencies or no material map";
    return res;
  }
  for (double t : phase.theta0)
    if (!(t != 0) || !std::isfinite(t)) {
      res.message = phase.name + ": base coordinates must be finite and non-zero";
      return res;
    }
  for (int j = 0; j < nj; ++j)
    if (!(phase.measured_hz[j] > 0) ||
        (j > 0 && !(phase.measured_hz[j] > phase.measured_hz[j - 1]))) {
      res.message = phase.name + ": measured frequencies must be positive and strictly ascending";
      return res;
    }
  res.alpha.assign(nt, 0.0);
  res.theta = phase.theta0;

  auto theta_of = [&](const std::vector<double>& alpha) {
    std::vector<double> th(nt);
    for (int n = 0; n < nt; ++n) th[n] = phase.theta0[n] * (1.0 + alpha[n]);
    return th;
  };

  model::PiezoMaterialE mat0;
  try {
    mat0 = phase.material(phase.theta0);
  } catch (const std::invalid_argument& e) {
    res.status = UpdateStatus::non_physical;
    res.message = phase.name + ": base model is not physical: " + e.what();
    return res;
  }
  model::ModalResult base = solver.solve(mat0, phase.electrodes, opt.modal);
  if (!base.converged) {
    res.status = UpdateStatus::solver_failure;
    res.message = phase.name + ": modal solve of the base model failed: " + base.message;
    return res;
  }
  const std::vector<int> act = active_modes(base);
  if (static_cast<int>(act.size()) < nj) {
    res.status = UpdateStatus::too_few_modes;
    std::ostringstream s;
    s << phase.name << ": " << nj << " measured frequencies but only " << act.size()
      << " electrically active " << model::to_string(phase.electrodes)
      << " model modes among the lowest " << opt.modal.n_modes << " (increase n_modes)";
    res.message = s.str();
    return res;
  }
  const int nu = tube.n_u();
  Eigen::MatrixXd phi(nu, nj);
  Eigen::VectorXd lambda_star(nj);
  for (int j = 0; j < nj; ++j) {
    phi.col(j) = base.shapes.col(act[j]);
    res.model_hz_initial.push_back(base.modes[act[j]].frequency_hz);
    res.mode_index.push_back(act[j]);
    lambda_star[j] = std::pow(2.0 * M_PI * phase.measured_hz[j], 2);
  }
  res.model_hz = res.model_hz_initial;

  // K_n = θ0_n ∂K/∂θ_n at the base model, as weight directions (eqs 239-240, 244).
  std::vector<model::MaterialWeights> dw(nt);
  try {
    for (int n = 0; n < nt; ++n) {
      auto mat_n = [&](double x) {
        std::vector<double> th = phase.theta0;
        th[n] = x;
        return phase.material(th);
      };
      const auto t = weight_tangent(mat_n, phase.theta0[n]);
      for (int p = 0; p < model::kNumMaterialParams; ++p) dw[n][p] = phase.theta0[n] * t[p];
    }
  } catch (const std::invalid_argument& e) {
    res.status = UpdateStatus::non_physical;
    res.message = phase.name + ": base model at the edge of the physical domain: " + e.what();
    return res;
  }
  const CondensedStiffness k0(tube, mat0, phase.electrodes);
  const model::SpMat mass = tube.mass(opt.modal.end_mass_fraction);  // M + f·ΔM (end-face mass)

  Eigen::MatrixXd phi_star = phi;
  for (int it = 1; it <= opt.max_iterations; ++it) {
    Eigen::MatrixXd b_prev;  // Φ_iᵀ K(θ_{k−1}) Φ*_j
    if (it == 1) {
      b_prev = k0.bilinear(phi, phi_star);
    } else {
      model::PiezoMaterialE mat;
      try {
        mat = phase.material(theta_of(res.alpha));
      } catch (const std::invalid_argument& e) {
        res.status = UpdateStatus::non_physical;
        res.message = phase.name + ": iterate " + std::to_string(it - 1) +
                      " left the physical domain: " + e.what();
        return res;
      }
      model::ModalResult r = solver.solve(mat, phase.electrodes, opt.modal);
      if (!r.converged) {
        res.status = UpdateStatus::solver_failure;
        res.message = phase.name + ": modal solve failed at iteration " + std::to_string(it) +
                      ": " + r.message;
        return res;
      }
      // Follow each paired mode by MAC against the previous iterate's shape.
      const Eigen::MatrixXd cross = phi_star.transpose() * (mass * r.shapes);
      Eigen::MatrixXd next(nu, nj);
      std::vector<int> used;
      for (int j = 0; j < nj; ++j) {
        int best = -1;
        double mac1 = 0, mac2 = 0;
        for (int c = 0; c < cross.cols(); ++c) {
          if (r.modes[c].omega <= 0) continue;
          const double mac = cross(j, c) * cross(j, c);  // shapes are M-normalised
          if (mac > mac1) {
            mac2 = mac1;
            mac1 = mac;
            best = c;
          } else if (mac > mac2) {
            mac2 = mac;
          }
        }
        res.min_mac = std::min(res.min_mac, mac1);
        if (best < 0 || mac1 < opt.mac_min || mac1 - mac2 < opt.mac_margin ||
            std::find(used.begin(), used.end(), best) != used.end()) {
          std::ostringstream s;
          s.precision(4);
          s << phase.name << ": ambiguous pairing at iteration " << it << " for measured mode "
            << j + 1 << " (" << phase.measured_hz[j] << " Hz): best MAC " << mac1 << ", runner-up "
            << mac2 << " (need >= " << opt.mac_min << " and a margin of " << opt.mac_margin << ")";
          res.status = UpdateStatus::ambiguous_pairing;
          res.message = s.str();
          return res;
        }
        used.push_back(best);
        next.col(j) = r.shapes.col(best);
        res.model_hz[j] = r.modes[best].frequency_hz;
        res.mode_index[j] = best;
      }
      phi_star = std::move(next);
      b_prev = CondensedStiffness(tube, mat, phase.electrodes).bilinear(phi, phi_star);
    }
    const Eigen::MatrixXd mx = phi.transpose() * (mass * phi_star);
    const Eigen::MatrixXd kx = k0.bilinear(phi, phi_star);
    std::vector<Eigen::MatrixXd> an(nt);
    Eigen::MatrixXd rem = b_prev - kx;
    for (int n = 0; n < nt; ++n) {
      an[n] = k0.dbilinear(dw[n], phi, phi_star);
      rem -= res.alpha[n] * an[n];
    }
    std::vector<std::pair<int, int>> pairs;
    for (int i = 0; i < nj; ++i)
      for (int j = 0; j < nj; ++j)
        if ((i == j || opt.cross_modes) && std::abs(mx(i, j)) >= opt.min_cross)
          pairs.emplace_back(i, j);
    Eigen::MatrixXd g(static_cast<Eigen::Index>(pairs.size()), nt);
    Eigen::VectorXd f(static_cast<Eigen::Index>(pairs.size()));
    for (std::size_t m = 0; m < pairs.size(); ++m) {
      const auto [i, j] = pairs[m];
      for (int n = 0; n < nt; ++n) g(m, n) = an[n](i, j) / kx(i, j);    // eq. 182
      f[m] = (lambda_star[j] * mx(i, j) - rem(i, j)) / kx(i, j) - 1.0;  // eqs 185-187
    }
    const TsvdSolution sol = solve_tsvd(g, f, opt.svd_rel_tol);  // eq. 193
    res.equations = static_cast<int>(pairs.size());
    res.rank = sol.rank;
    // The fixed-point step can overshoot out of the physical domain far from
    // the solution (a ±12 % start drives ν12 past its bound): the step from
    // the current iterate is halved until the material is physical again
    // (at most 12 times; the fixed point itself is unchanged).
    std::vector<double> next_alpha(sol.x.data(), sol.x.data() + nt);
    for (int halving = 0; halving <= 12; ++halving) {
      bool physical = true;
      try {
        (void)phase.material(theta_of(next_alpha));
      } catch (const std::invalid_argument&) {
        physical = false;
      }
      if (physical) break;
      if (halving == 12) {
        res.status = UpdateStatus::non_physical;
        res.message = phase.name + ": iterate " + std::to_string(it) +
                      " stays outside the physical domain after 12 step halvings";
        res.theta = theta_of(res.alpha);
        return res;
      }
      for (int n = 0; n < nt; ++n) next_alpha[n] = 0.5 * (next_alpha[n] + res.alpha[n]);
      ++res.step_halvings;
    }
    double delta = 0;
    for (int n = 0; n < nt; ++n) {
      delta = std::max(delta, std::abs(next_alpha[n] - res.alpha[n]));
      res.alpha[n] = next_alpha[n];
    }
    res.alpha_history.push_back(res.alpha);
    res.iterations = it;
    if (!std::isfinite(delta)) {
      res.status = UpdateStatus::non_physical;
      res.message = phase.name + ": non-finite correction at iteration " + std::to_string(it);
      return res;
    }
    if (delta < opt.tolerance) {
      res.status = UpdateStatus::converged;
      break;
    }
  }
  res.theta = theta_of(res.alpha);
  if (res.status != UpdateStatus::converged && res.step_halvings > 0) {
    // Held at the edge of the domain by the halving: the features ask for a
    // non-physical material.
    res.status = UpdateStatus::non_physical;
    res.message = phase.name + ": the measured frequencies pull the model out of the physical domain (" +
                  std::to_string(res.step_halvings) + " steps halved at its edge, not converged after " +
                  std::to_string(res.iterations) + " iterations)";
    return res;
  }
  if (res.status != UpdateStatus::converged) {
    res.status = UpdateStatus::max_iterations;
    std::ostringstream s;
    s.precision(4);
    s << phase.name << ": not converged after " << res.iterations << " iterations (last |Δα| "
      << "above " << opt.tolerance << "); model " << hz_list(res.model_hz) << " Hz vs measured "
      << hz_list(phase.measured_hz) << " Hz";
    res.message = s.str();
  }
  return res;
}

}  // namespace piezo::update
