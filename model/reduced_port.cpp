#include "model/reduced_port.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <vector>

#include "model/work_counters.hpp"

namespace piezo::model {

namespace {

// An orthonormal basis (in the inner product `b`, or the Euclidean one when
// b is null) of the columns' span: each column first scaled to unit norm
// (the static shapes are ~1e-10 m beside unit-mass modes), then the Gram
// matrix's eigenvectors, directions below 1e-12 of the largest dropped.
Eigen::MatrixXd orthonormal(const Eigen::MatrixXd& cols, const SpMat* b) {
  Eigen::MatrixXd v = cols;
  for (Eigen::Index k = 0; k < v.cols(); ++k) {
    const double n2 = b ? v.col(k).dot(*b * v.col(k)) : v.col(k).squaredNorm();
    if (n2 > 0) v.col(k) /= std::sqrt(n2);
  }
  const Eigen::MatrixXd gram = b ? Eigen::MatrixXd(v.transpose() * (*b * v)) : Eigen::MatrixXd(v.transpose() * v);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(gram);
  const double gmax = es.eigenvalues().maxCoeff();
  Eigen::Index keep = 0;
  for (Eigen::Index k = 0; k < es.eigenvalues().size(); ++k) keep += es.eigenvalues()[k] > 1e-24 * gmax;
  return v * (es.eigenvectors().rightCols(keep) *
              es.eigenvalues().tail(keep).cwiseSqrt().cwiseInverse().asDiagonal());
}

Eigen::MatrixXd symmetric(const Eigen::MatrixXd& a) { return 0.5 * (a + a.transpose()); }

}  // namespace

ReducedPortSpace::ReducedPortSpace(std::shared_ptr<const TubeModel> half, const PiezoMaterialE& reference,
                                   bool estimates)
    : model(std::move(half)), estimates(estimates) {
  if (!model || model->extent() != TubeExtent::upper_half)
    throw std::invalid_argument("ReducedPortSpace: needs the upper half of a tube (TubeModel::upper_half)");
  nu = model->n_u();
  np1 = model->n_phi();
  const SplitSystem& sys = model->system();
  const MaterialParam c[5] = {MaterialParam::c11, MaterialParam::c12, MaterialParam::c13, MaterialParam::c33,
                              MaterialParam::c44};
  const MaterialParam e[3] = {MaterialParam::e31, MaterialParam::e33, MaterialParam::e15};
  const MaterialParam eps[2] = {MaterialParam::eps11, MaterialParam::eps33};
  // (The split matrices share the whole system's pattern: their own entries only, pruned.)
  for (int k = 0; k < 5; ++k) k_uu[static_cast<std::size_t>(k)] = SpMat(sys.matrix(c[k]).topLeftCorner(nu, nu)).pruned(0.0);
  for (int k = 0; k < 3; ++k) {
    k_up[static_cast<std::size_t>(k)] = SpMat(sys.matrix(e[k]).topRightCorner(nu, np1)).pruned(0.0);
    k_pu[static_cast<std::size_t>(k)] = SpMat(k_up[static_cast<std::size_t>(k)].transpose());
  }
  for (int k = 0; k < 2; ++k) k_pp[static_cast<std::size_t>(k)] = SpMat(sys.matrix(eps[k]).bottomRightCorner(np1, np1)).pruned(0.0);
  m = model->mass(0.0);
  dm = SpMat(model->mass(1.0) - m);
  on_plane.assign(static_cast<std::size_t>(nu), 0);
  for (int dof : model->symmetry_plane_dofs()) on_plane[static_cast<std::size_t>(dof)] = 1;
  if (!estimates) return;  // (the factorisations below are the check's only)
  // M with the mid-plane's u_z constrained (identity rows), for ‖r‖_M⁻¹.
  std::vector<Eigen::Triplet<double>> t;
  for (int col = 0; col < m.outerSize(); ++col)
    for (SpMat::InnerIterator it(m, col); it; ++it)
      if (!on_plane[static_cast<std::size_t>(it.row())] && !on_plane[static_cast<std::size_t>(it.col())])
        t.emplace_back(static_cast<int>(it.row()), static_cast<int>(it.col()), it.value());
  for (int dof : model->symmetry_plane_dofs()) t.emplace_back(dof, dof, 1.0);
  SpMat mc(nu, nu);
  mc.setFromTriplets(t.begin(), t.end());
  m_factor.compute(mc);
  if (m_factor.info() != Eigen::Success) throw std::runtime_error("ReducedPortSpace: M not positive definite");
  // The isotropic class has εS11 = 0 (model/material.hpp): K_ΦΦ = εS33·K_ε33
  // on the interior potentials, one factorisation for every material of it.
  eps33_factor.compute(SpMat(-k_pp[1].topLeftCorner(np1 - 1, np1 - 1)));
  eps33_ok = eps33_factor.info() == Eigen::Success;
  auto sf = std::make_shared<CoupledFactor>(*model);
  if (!sf->factorize(weights(reference), 0.0, Electrodes::short_circuit, model->symmetry_plane_dofs()))
    throw std::runtime_error("ReducedPortSpace: singular static system at the reference material");
  static_factor = std::move(sf);
}

std::optional<ReducedPort> ReducedPort::build(std::span<const PortVectors> snaps, const PiezoMaterialE& centre,
                                              const ModalOptions& opt, std::shared_ptr<const ReducedPortSpace> space,
                                              bool estimates) {
  if (snaps.empty() || !snaps[0].model) return std::nullopt;
  const auto& model = snaps[0].model;
  Eigen::Index nu_cols = 0, np_cols = 0;
  for (const auto& s : snaps) {
    if (s.model != model) return std::nullopt;
    nu_cols += s.u.cols();
    np_cols += s.phi.cols();
  }
  if (!space) space = std::make_shared<const ReducedPortSpace>(model, centre, estimates);
  if (estimates && !space->estimates) return std::nullopt;
  if (space->model != model) return std::nullopt;
  const ReducedPortSpace& sp = *space;
  const int nu = sp.nu, np = sp.np1 - 1;
  Eigen::MatrixXd us(nu, nu_cols), ps(np, np_cols);
  Eigen::Index cu = 0, cp = 0;
  for (const auto& s : snaps) {
    us.middleCols(cu, s.u.cols()) = s.u;
    ps.middleCols(cp, s.phi.cols()) = s.phi;
    cu += s.u.cols();
    cp += s.phi.cols();
  }
  ReducedPort rp;
  rp.space_ = space;
  rp.end_mass_ = opt.end_mass_fraction;
  rp.n_modes_ = opt.n_modes / 2 + 1;  // the half's, as ModalSolver::port_model
  const SpMat m_f = opt.end_mass_fraction == 0.0 ? sp.m : SpMat(sp.m + opt.end_mass_fraction * sp.dm);
  rp.v_u_ = orthonormal(us, &m_f);
  const Eigen::MatrixXd v_int = orthonormal(ps, nullptr);
  rp.r_ = static_cast<int>(rp.v_u_.cols());
  rp.q_ = static_cast<int>(v_int.cols());
  if (rp.r_ <= rp.n_modes_ || rp.q_ < 1) return std::nullopt;
  // Φ's basis with the electrode's V as its last vector.
  rp.v_p_ = Eigen::MatrixXd::Zero(sp.np1, rp.q_ + 1);
  rp.v_p_.topLeftCorner(np, rp.q_) = v_int;
  rp.v_p_(np, rp.q_) = 1.0;
  // The blocks, projected (each split matrix lives in one block of K).
  for (std::size_t k = 0; k < 5; ++k) {
    Eigen::MatrixXd kv = sp.k_uu[k] * rp.v_u_;
    rp.kuu_[k] = symmetric(rp.v_u_.transpose() * kv);
    if (estimates) rp.kuu_v_[k] = std::move(kv);
  }
  for (std::size_t k = 0; k < 3; ++k) {
    Eigen::MatrixXd kv = sp.k_up[k] * rp.v_p_;
    rp.kup_[k] = rp.v_u_.transpose() * kv;
    if (estimates) {
      rp.kup_v_[k] = std::move(kv);
      rp.kpu_v_[k] = sp.k_pu[k] * rp.v_u_;
    }
  }
  for (std::size_t k = 0; k < 2; ++k) {
    Eigen::MatrixXd kv = sp.k_pp[k] * rp.v_p_;
    rp.kpp_[k] = symmetric(rp.v_p_.transpose() * kv);
    if (estimates) rp.kpp_v_[k] = std::move(kv);
  }
  Eigen::MatrixXd mv = sp.m * rp.v_u_, dmv = sp.dm * rp.v_u_;
  rp.m0_ = symmetric(rp.v_u_.transpose() * mv);
  rp.dm_ = symmetric(rp.v_u_.transpose() * dmv);
  if (estimates) {
    rp.mv_ = std::move(mv);
    rp.dmv_ = std::move(dmv);
  }
  rp.estimates_ = estimates;
  return rp;
}

std::optional<ReducedPort> ReducedPort::build(ModalSolver& solver, std::span<const Point> points,
                                              const ModalOptions& opt, std::shared_ptr<const ReducedPortSpace> space,
                                              bool estimates) {
  if (points.empty()) return std::nullopt;
  std::vector<PortVectors> snaps;
  snaps.reserve(points.size());
  for (const auto& pt : points) {
    ModalOptions o = opt;
    o.end_mass_fraction = pt.end_mass_fraction;
    auto v = solver.port_vectors(pt.material, o);
    if (!v) return std::nullopt;
    snaps.push_back(std::move(*v));
  }
  ModalOptions o = opt;
  o.end_mass_fraction = points[0].end_mass_fraction;
  return build(snaps, points[0].material, o, std::move(space), estimates);
}

ModalPortModel ReducedPort::port_model(const PiezoMaterialE& material, double end_mass_fraction,
                                       Bound* bound) const {
  g_reduced_port_models.fetch_add(1, std::memory_order_relaxed);  // model/work_counters.hpp
  const auto w = weights(material);
  const int q = q_;
  // K = Σ w_p K_p by blocks: U×U (the cE's), U×[Φ_int V] (the e's), [Φ_int V]² (the εS's).
  Eigen::MatrixXd kuu = w[0] * kuu_[0];
  for (std::size_t k = 1; k < 5; ++k) kuu.noalias() += w[k] * kuu_[k];
  Eigen::MatrixXd kup = w[5] * kup_[0];
  for (std::size_t k = 1; k < 3; ++k) kup.noalias() += w[5 + k] * kup_[k];
  Eigen::MatrixXd kpp = w[8] * kpp_[0] + w[9] * kpp_[1];
  ModalPortModel out;
  out.reduced_basis = true;
  out.end_mass_fraction = end_mass_fraction;
  const double df = end_mass_fraction - end_mass_;
  const Eigen::MatrixXd m_r = m0_ + end_mass_fraction * dm_;
  if (material.eps_s33 > 0) out.eps_t_over_s = to_d_form(material).eps_t33 / material.eps_s33;
  // −K_ΦΦ is positive definite (K_ΦΦ = −∫B_φᵀεS B_φ): condense Φ_int.
  const Eigen::LLT<Eigen::MatrixXd> npp(-kpp.topLeftCorner(q, q));
  if (npp.info() != Eigen::Success) {
    out.converged = false;
    return out;
  }
  const Eigen::MatrixXd kui = kup.leftCols(q);
  const Eigen::MatrixXd x = npp.solve(kui.transpose());      // (−K_ΦΦ)⁻¹K_ΦU
  const Eigen::VectorXd y_c = npp.solve(kpp.col(q).head(q));  // (−K_ΦΦ)⁻¹K_ΦV
  Eigen::MatrixXd ksc = kuu + kui * x;
  ksc = symmetric(ksc);
  out.c_clamped = -(kpp.col(q).head(q).dot(y_c) + kpp(q, q));
  const Eigen::VectorXd g = kui * y_c + kup.col(q);
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(ksc, m_r);
  const Eigen::LLT<Eigen::MatrixXd> kf(ksc);
  if (es.info() != Eigen::Success || kf.info() != Eigen::Success) {
    out.converged = false;
    return out;
  }
  for (int k = 0; k < n_modes_; ++k) {
    const Eigen::VectorXd z = es.eigenvectors().col(k);  // zᵀM_r z = 1
    // Sign convention of ModalSolver::solve: largest |u| component positive.
    const Eigen::VectorXd phi = v_u_ * z;
    Eigen::Index imax;
    phi.cwiseAbs().maxCoeff(&imax);
    const double sign = phi[imax] < 0 ? -1.0 : 1.0;
    PortMode m;
    m.omega = std::sqrt(std::max(es.eigenvalues()[k], 0.0));
    m.participation = sign * g.dot(z);
    m.kappa = z.dot(kuu * z);
    m.symmetric = true;  // the upper half carries the symmetric modes only
    out.modes.push_back(m);
  }
  // Static: K_sc u_s = −g, C_static = C0 + gᵀK_sc⁻¹g.
  const Eigen::VectorXd u_s = kf.solve(-g);
  out.c_static = out.c_clamped - g.dot(u_s);
  if (bound) *bound = estimates_ ? check(w, df, x, g, es.eigenvectors(), es.eigenvalues(), out) : Bound{INFINITY, INFINITY};
  add_residual_mode(out, u_s.dot(m_r * u_s));
  half_to_whole(out);
  return out;
}

bool ReducedPort::Bound::acceptable() const {
  return omega <= kOmegaTolerance && participation <= kParticipationEstimate;
}

ReducedPort::Bound ReducedPort::check(const MaterialWeights& w, double df, const Eigen::MatrixXd& x,
                                      const Eigen::VectorXd& g, const Eigen::MatrixXd& z,
                                      const Eigen::VectorXd& lambda, const ModalPortModel& half) const {
  Bound b;
  const ReducedPortSpace& sp = *space_;
  const int q = q_, nu = sp.nu, np = sp.np1 - 1;
  // (−K_ΦΦ)⁻¹ on Φ_int at this material.
  std::optional<Eigen::SimplicialLDLT<SpMat>> own;
  const Eigen::SimplicialLDLT<SpMat>* pp = nullptr;
  double pp_scale = 1.0;
  if (w[8] == 0.0 && sp.eps33_ok && w[9] > 0) {
    pp = &sp.eps33_factor;
    pp_scale = 1.0 / w[9];
  } else {
    own.emplace(SpMat(-(w[8] * sp.k_pp[0] + w[9] * sp.k_pp[1]).topLeftCorner(np, np)));
    if (own->info() != Eigen::Success) return {INFINITY, INFINITY};
    pp = &*own;
  }
  // K·W by blocks at this material: U rows [K_UU V_U, K_UΦ V_Φ], Φ rows [K_ΦU V_U, K_ΦΦ V_Φ].
  Eigen::MatrixXd uu = w[0] * kuu_v_[0], up = w[5] * kup_v_[0], pu = w[5] * kpu_v_[0];
  for (std::size_t k = 1; k < 5; ++k) uu.noalias() += w[k] * kuu_v_[k];
  for (std::size_t k = 1; k < 3; ++k) {
    up.noalias() += w[5 + k] * kup_v_[k];
    pu.noalias() += w[5 + k] * kpu_v_[k];
  }
  const Eigen::MatrixXd ppv = w[8] * kpp_v_[0] + w[9] * kpp_v_[1];
  SpMat kup_int = w[5] * sp.k_up[0];
  for (std::size_t k = 1; k < 3; ++k) kup_int += w[5 + k] * sp.k_up[k];
  // The exactly condensed residual of [z; φ; v] (reduced coordinates), with
  // `m_part` the mass term on U: r = r_U − K_UΦ K_ΦΦ⁻¹ r_Φ.
  auto sc_residual = [&](const Eigen::VectorXd& zu, const Eigen::VectorXd& zp, const Eigen::VectorXd& m_part) {
    Eigen::VectorXd r_u = uu * zu + up * zp - m_part;
    const Eigen::VectorXd r_p = pu * zu + ppv * zp;
    Eigen::VectorXd t = Eigen::VectorXd::Zero(np + 1);
    t.head(np) = pp_scale * pp->solve(Eigen::VectorXd(r_p.head(np)));  // (−K_ΦΦ)⁻¹ r_Φ
    r_u.noalias() += kup_int * t;
    for (int i = 0; i < nu; ++i)
      if (sp.on_plane[static_cast<std::size_t>(i)]) r_u[i] = 0.0;  // (a reaction there)
    return r_u;
  };
  auto m_inv_norm = [&](const Eigen::VectorXd& v) { return std::sqrt(std::max(0.0, v.dot(sp.m_factor.solve(v)))); };
  // Every Ritz pair's participation: together they carry the whole static
  // share C_static − C0 of the reduced model (Σ p_j²/ω_j² = gᵀK_sc⁻¹g).
  const Eigen::VectorXd p_all = z.transpose() * g;
  const std::vector<int>& plane = sp.model->symmetry_plane_dofs();
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(nu + np + 1), y;
  for (int k = 0; k < n_modes_; ++k) {
    const double p = half.modes[static_cast<std::size_t>(k)].participation, om = half.modes[static_cast<std::size_t>(k)].omega;
    if (!(p * p > 1e-4 * om * om * half.c_clamped)) continue;  // not seen at the port
    Eigen::VectorXd zp = Eigen::VectorXd::Zero(q + 1);
    zp.head(q) = x * z.col(k);
    Eigen::VectorXd mz = mv_ * z.col(k);
    mz.noalias() += (end_mass_ + df) * (dmv_ * z.col(k));
    const Eigen::VectorXd r_sc = sc_residual(z.col(k), zp, lambda[k] * mz);
    const double eta = m_inv_norm(r_sc);
    // The Rayleigh quotient of the exact operator is ω² + φᵀr (the reduced
    // condensation's share), the exact eigenvalue within η²/δ of it.
    const double rayleigh = std::abs((v_u_ * z.col(k)).dot(r_sc));
    double gap = INFINITY;
    if (k > 0) gap = lambda[k] - lambda[k - 1];
    if (k + 1 < lambda.size()) gap = std::min(gap, lambda[k + 1] - lambda[k]);
    gap = std::max(gap - eta, 0.0);  // (the exact neighbours may be closer by η)
    b.omega = std::max(b.omega, gap > 0 ? (rayleigh + eta * eta / gap) / (2.0 * lambda[k]) : INFINITY);
    // Δp = −Σ_j p_j φ_jᵀr/(λ_j − λ) to first order, so by Cauchy–Schwarz
    // |Δp| ≤ (Σ_j p_j²λ_j/(λ_j − λ)²)^½ · (rᵀK_sc⁻¹r)^½; K_sc at the
    // space's reference (factorised once) stands for K_sc here (×2), and
    // the Ritz values for the exact ones (×2).
    double a2 = 0;
    for (Eigen::Index j = 0; j < lambda.size(); ++j) {
      if (j == k) continue;
      const double dl = lambda[j] - lambda[k];
      a2 += dl != 0 ? p_all[j] * p_all[j] * lambda[j] / (dl * dl) : INFINITY;
    }
    rhs.head(nu) = r_sc;
    for (int dof : plane) rhs[dof] = 0.0;
    sp.static_factor->solve(rhs, y);
    const double knorm2 = 2.0 * std::max(0.0, r_sc.dot(y.head(nu)));
    b.participation = std::max(b.participation, std::sqrt(2.0 * a2 * knorm2) / std::abs(p));
  }
  return b;
}

}  // namespace piezo::model
