#include "update/mode_shape_cmcm.hpp"

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "numerics/gauss_newton.hpp"
#include "update/cmcm.hpp"

namespace piezo::update {

using model::Electrodes;
using model::SpMat;

ModalData elastic_modes(const model::ModalResult& r, int n) {
  ModalData d;
  std::vector<int> idx;
  for (std::size_t k = 0; k < r.modes.size() && static_cast<int>(idx.size()) < n; ++k)
    if (r.modes[k].omega > 0) idx.push_back(static_cast<int>(k));
  d.shapes.resize(r.shapes.rows(), static_cast<Eigen::Index>(idx.size()));
  d.lambda.resize(static_cast<Eigen::Index>(idx.size()));
  for (std::size_t c = 0; c < idx.size(); ++c) {
    d.shapes.col(static_cast<Eigen::Index>(c)) = r.shapes.col(idx[c]);
    d.lambda[static_cast<Eigen::Index>(c)] = r.modes[idx[c]].omega * r.modes[idx[c]].omega;
  }
  return d;
}

const char* to_string(ModeShapeStaging s) {
  return s == ModeShapeStaging::seed ? "seed (D.1 then D.2)" : "joint";
}

const char* mode_shape_unknown_name(int n) {
  static constexpr const char* names[kModeShapeUnknowns] = {
      "cE11",          "cE12",          "cE13",         "cE33",
      "cE44",          "e31^2/epsS33",  "e33^2/epsS33", "e15^2/epsS33",
      "e31e33/epsS33", "e31e15/epsS33", "e33e15/epsS33"};
  if (n < 0 || n >= kModeShapeUnknowns)
    throw std::invalid_argument("mode_shape_unknown_name: index");
  return names[n];
}

double eps_s33_d11(const model::PiezoMaterialE& elastic, double g31, double g33, double eps_t33) {
  const Eigen::Matrix<double, 6, 6> s = model::to_matrices(elastic).elastic.inverse();
  // IEEE indices, 3 = poling: s11 = s(0,0), s12 = s(0,1), s13 = s(0,2), s33 = s(2,2).
  const double q = 2.0 * (s(0, 0) + s(0, 1)) * g31 * g31 + 4.0 * s(0, 2) * g31 * g33 +
                   s(2, 2) * g33 * g33;  // eq. D.11 divided by εS33
  return eps_t33 / (1.0 + q);
}

namespace {

// Coupling pairs (k, l) of the lifted unknowns 5..10: b1, b2, b3, then the cross terms.
constexpr std::array<std::pair<int, int>, 6> kPairs{
    {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {0, 2}, {1, 2}}};

// Bilinear forms Φᵀ(·)Φ* of the pieces of the condensed stiffness of one
// electrode condition (split matrices of the TubeModel, nothing re-assembled).
struct Terms {
  std::array<Eigen::MatrixXd, 5> el;                  // Φᵀ K_cn Φ* (eq. 234)
  std::array<std::array<Eigen::MatrixXd, 3>, 3> cpl;  // Φᵀ K_ek N⁻¹ K_elᵀ Φ* (D.4-D.9 without b)
  Eigen::MatrixXd m;                                  // Φᵀ M Φ*
};

Terms make_terms(const model::TubeModel& tube, Electrodes electrodes, const Eigen::MatrixXd& x,
                 const Eigen::MatrixXd& y) {
  const auto& s = tube.split();
  const int nc = electrodes == Electrodes::open_circuit ? tube.n_phi() : tube.n_phi() - 1;
  Terms t;
  for (int n = 0; n < 5; ++n) t.el[n] = x.transpose() * (s.k_c[n] * y);
  t.m = x.transpose() * (s.m * y);
  const SpMat neg = -SpMat(s.k_eps[1].topLeftCorner(nc, nc));  // N = −K_εS33 (eq. 246)
  Eigen::SimplicialLDLT<SpMat> n_fac(neg);
  if (n_fac.info() != Eigen::Success)
    throw std::runtime_error("mode_shape_cmcm: K_εS33 block is singular");
  std::array<Eigen::MatrixXd, 3> bx, py;
  for (int k = 0; k < 3; ++k) {
    const SpMat kt = SpMat(s.k_e[k].transpose()).topRows(nc);
    bx[k] = kt * x;
    py[k] = n_fac.solve(Eigen::MatrixXd(kt * y));
  }
  for (int k = 0; k < 3; ++k)
    for (int l = 0; l < 3; ++l) t.cpl[k][l] = bx[k].transpose() * py[l];
  return t;
}

struct Base {
  std::array<double, 5> c{};
  std::array<double, 3> e{};
  double eps = 0;
  double p(int k, int l) const { return e[k] * e[l] / eps; }
};

// Direction of unknown u at pair (i, j): θ0 ∂K/∂θ (eq. 173's K_n).
double direction(const Terms& t, const Base& b, int u, int i, int j) {
  if (u < 5) return b.c[u] * t.el[u](i, j);
  const auto [k, l] = kPairs[u - 5];
  if (k == l) return b.p(k, k) * t.cpl[k][k](i, j);
  return b.p(k, l) * (t.cpl[k][l](i, j) + t.cpl[l][k](i, j));
}

// Column of unknown u. With the seed's linearisation of D.10,
// √((1+α_k)(1+α_l)) ≈ 1 + (α_k + α_l)/2, the cross terms have no unknown of
// their own: b_k's column takes half of each cross term it enters.
double column(const Terms& t, const Base& b, int u, int i, int j, bool linearised) {
  double d = direction(t, b, u, i, j);
  if (linearised && u >= 5 && u < 8)
    for (int c = 8; c < kModeShapeUnknowns; ++c) {
      const auto [k, l] = kPairs[c - 5];
      if (k == u - 5 || l == u - 5) d += 0.5 * direction(t, b, c, i, j);
    }
  return d;
}

double k0(const Terms& t, const Base& b, int i, int j) {
  double v = 0;
  for (int u = 0; u < kModeShapeUnknowns; ++u) v += direction(t, b, u, i, j);
  return v;
}

struct Block {
  Electrodes electrodes;
  const Terms* terms;
  const ModalData* target;
};

// Rows of eq. 187 (β = 0) for the unknowns `cols`; the unknowns in `fixed`
// with values `alpha` are moved to the right-hand side.
ModeShapeEquations equations(const std::vector<Block>& blocks, const Base& b,
                             const std::vector<int>& cols, const std::vector<int>& fixed,
                             const std::array<double, kModeShapeUnknowns>& alpha, double min_cross,
                             bool cross_modes, bool linearised) {
  ModeShapeEquations eq;
  eq.unknowns = cols;
  std::vector<Eigen::VectorXd> rows;
  std::vector<double> rhs;
  for (const Block& bl : blocks) {
    const Terms& t = *bl.terms;
    for (Eigen::Index i = 0; i < t.m.rows(); ++i) {
      for (Eigen::Index j = 0; j < t.m.cols(); ++j) {
        if (!cross_modes && i != j) continue;
        const double kij = k0(t, b, static_cast<int>(i), static_cast<int>(j));
        const double mij = t.m(i, j);
        if (std::abs(mij) < min_cross || kij == 0) continue;  // both sides M-normalised
        Eigen::VectorXd row(static_cast<Eigen::Index>(cols.size()));
        for (std::size_t c = 0; c < cols.size(); ++c)
          row[static_cast<Eigen::Index>(c)] =
              column(t, b, cols[c], static_cast<int>(i), static_cast<int>(j), linearised) /
              kij;  // eq. 182
        // eqs 180-181/185-187: λ*_j Φ_iᵀMΦ*_j / Φ_iᵀKΦ*_j − 1 (= λ*_j/λ_i − 1 for exact Φ_i).
        double f = bl.target->lambda[j] * mij / kij - 1.0;
        for (int u : fixed)
          f -= alpha[u] * column(t, b, u, static_cast<int>(i), static_cast<int>(j), linearised) /
               kij;
        rows.push_back(row);
        rhs.push_back(f);
        eq.electrodes.push_back(bl.electrodes);
        eq.pairs.emplace_back(static_cast<int>(i), static_cast<int>(j));
      }
    }
  }
  eq.g.resize(static_cast<Eigen::Index>(rows.size()), static_cast<Eigen::Index>(cols.size()));
  eq.f.resize(static_cast<Eigen::Index>(rows.size()));
  for (std::size_t r = 0; r < rows.size(); ++r) {
    eq.g.row(static_cast<Eigen::Index>(r)) = rows[r].transpose();
    eq.f[static_cast<Eigen::Index>(r)] = rhs[r];
  }
  return eq;
}

Eigen::VectorXd independence(const Eigen::MatrixXd& g) {
  const Eigen::Index nc = g.cols();
  Eigen::VectorXd ind = Eigen::VectorXd::Ones(nc);
  if (nc < 2) return ind;
  Eigen::MatrixXd gn = g;
  for (Eigen::Index c = 0; c < nc; ++c)
    if (gn.col(c).norm() > 0) gn.col(c) /= gn.col(c).norm();
  for (Eigen::Index c = 0; c < nc; ++c) {
    Eigen::MatrixXd others(gn.rows(), nc - 1);
    for (Eigen::Index o = 0, k = 0; o < nc; ++o)
      if (o != c) others.col(k++) = gn.col(o);
    const Eigen::VectorXd proj =
        others * others.completeOrthogonalDecomposition().solve(Eigen::VectorXd(gn.col(c)));
    ind[c] = (gn.col(c) - proj).norm();
  }
  return ind;
}

// α of the physical unknowns θ = (x_n = cE_n/cE0_n, y_k = g_k/g0_k).
std::array<double, kModeShapeUnknowns> alpha_of(const std::array<double, 8>& th) {
  std::array<double, kModeShapeUnknowns> a{};
  for (int n = 0; n < 5; ++n) a[n] = th[n] - 1.0;
  for (int u = 5; u < kModeShapeUnknowns; ++u) {
    const auto [k, l] = kPairs[u - 5];
    a[u] = th[5 + k] * th[5 + l] - 1.0;
  }
  return a;
}

// ∂α_u/∂θ_v.
double dalpha(const std::array<double, 8>& th, int u, int v) {
  if (u < 5) return u == v ? 1.0 : 0.0;
  const auto [k, l] = kPairs[u - 5];
  double d = 0;
  if (v == 5 + k) d += th[5 + l];
  if (v == 5 + l) d += th[5 + k];
  return d;
}

double residual_norm(const ModeShapeEquations& eq,
                     const std::array<double, kModeShapeUnknowns>& a) {
  Eigen::VectorXd x(static_cast<Eigen::Index>(eq.unknowns.size()));
  for (std::size_t c = 0; c < eq.unknowns.size(); ++c)
    x[static_cast<Eigen::Index>(c)] = a[eq.unknowns[c]];
  return (eq.g * x - eq.f).norm();
}

// Gauss–Newton on the physical unknowns that enter `eq`, the others fixed.
int refine(const ModeShapeEquations& eq, std::array<double, 8>& th, int max_it, double rel_tol) {
  std::vector<int> free;  // θ_v that some column of eq depends on (y_k > 0, so ∂α/∂y ≠ 0)
  for (int v = 0; v < 8; ++v)
    for (int u : eq.unknowns)
      if (dalpha(th, u, v) != 0) {
        free.push_back(v);
        break;
      }
  numerics::GaussNewtonProblem gn;
  gn.linearise = [&](Eigen::VectorXd& r, Eigen::MatrixXd& j) {
    const auto a = alpha_of(th);
    Eigen::VectorXd x(static_cast<Eigen::Index>(eq.unknowns.size()));
    Eigen::MatrixXd da(static_cast<Eigen::Index>(eq.unknowns.size()),
                       static_cast<Eigen::Index>(free.size()));
    for (std::size_t c = 0; c < eq.unknowns.size(); ++c) {
      x[static_cast<Eigen::Index>(c)] = a[eq.unknowns[c]];
      for (std::size_t v = 0; v < free.size(); ++v)
        da(static_cast<Eigen::Index>(c), static_cast<Eigen::Index>(v)) =
            dalpha(th, eq.unknowns[c], free[v]);
    }
    r = eq.g * x - eq.f;
    j = eq.g * da;
  };
  gn.solve = [&](const Eigen::MatrixXd& j, const Eigen::VectorXd& minus_r) { return solve_tsvd(j, minus_r, rel_tol).x; };
  gn.apply = [&](const Eigen::VectorXd& step) {
    for (std::size_t v = 0; v < free.size(); ++v) th[free[v]] += step[static_cast<Eigen::Index>(v)];
  };
  return numerics::gauss_newton(gn, max_it, 1e-14);
}

}  // namespace

ModeShapeCmcmResult mode_shape_cmcm(const model::TubeModel& tube, model::ModalSolver& solver,
                                    const model::PiezoMaterialE& base,
                                    const ModeShapeTargets& targets,
                                    const ModeShapeCmcmOptions& opt) {
  model::validate(base, "mode_shape_cmcm");
  if (base.eps_s11 != 0)
    throw std::invalid_argument(
        "mode_shape_cmcm: Appendix D.2 assumes epsS11 = 0 in the base model");
  const Base b{{base.c_e11, base.c_e12, base.c_e13, base.c_e33, base.c_e44},
               {base.e31, base.e33, base.e15},
               base.eps_s33};
  for (double v : b.c)
    if (!(v != 0))
      throw std::invalid_argument("mode_shape_cmcm: zero elastic constant in the base");
  for (double v : b.e)
    if (!(v != 0))
      throw std::invalid_argument("mode_shape_cmcm: zero piezoelectric constant in the base");
  for (const ModalData* d : {&targets.short_circuit, &targets.open_circuit})
    if (d->shapes.rows() != tube.n_u() || d->shapes.cols() != d->lambda.size() ||
        d->lambda.size() == 0)
      throw std::invalid_argument(
          "mode_shape_cmcm: target shapes must be n_u x J with J eigenvalues, J > 0");
  if (!(targets.eps_t33 > 0)) throw std::invalid_argument("mode_shape_cmcm: eps_t33 must be > 0");
  if (opt.n_model_modes < 1)
    throw std::invalid_argument("mode_shape_cmcm: n_model_modes must be >= 1");

  ModeShapeCmcmResult res;
  res.staging = opt.staging;
  for (int k = 0; k < 3; ++k) res.b_base[k] = b.p(k, k);

  // Model modes (eq. 172) and the bilinear forms with the target shapes, per
  // electrode condition. Shapes M-normalised so that min_cross is relative.
  auto normalised = [&](ModalData d) {
    const Eigen::MatrixXd mx = tube.split().m * d.shapes;
    for (Eigen::Index c = 0; c < d.shapes.cols(); ++c)
      d.shapes.col(c) /= std::sqrt(d.shapes.col(c).dot(mx.col(c)));
    return d;
  };
  const ModalData tsc = normalised(targets.short_circuit), toc = normalised(targets.open_circuit);
  std::array<Terms, 2> terms;
  for (int e = 0; e < 2; ++e) {
    const Electrodes el = e == 0 ? Electrodes::short_circuit : Electrodes::open_circuit;
    const model::ModalResult r = solver.solve(base, el, opt.modal);
    if (!r.converged) {
      res.message = std::string("mode_shape_cmcm: modal solve of the base model failed (") +
                    model::to_string(el) + "): " + r.message;
      return res;
    }
    const ModalData md = elastic_modes(r, opt.n_model_modes);
    terms[e] = make_terms(tube, el, md.shapes, e == 0 ? tsc.shapes : toc.shapes);
  }
  const Block sc{Electrodes::short_circuit, &terms[0], &tsc};
  const Block oc{Electrodes::open_circuit, &terms[1], &toc};

  auto solve = [&](ModeShapeEquations& eq) {
    const TsvdSolution s = solve_tsvd(eq.g, eq.f, opt.svd_rel_tol);  // eqs 191-193
    eq.singular_values = s.singular_values;
    eq.rank = s.rank;
    eq.independence = independence(eq.g);
    eq.right_singular_vectors =
        Eigen::JacobiSVD<Eigen::MatrixXd>(eq.g, Eigen::ComputeThinV).matrixV();
    return s.x;
  };
  const bool lin = opt.linearise_cross_terms;
  const int n_unknowns = lin ? 8 : kModeShapeUnknowns;
  std::vector<int> elastic{0, 1, 2, 3, 4}, coupling, all;
  for (int u = 0; u < n_unknowns; ++u) {
    all.push_back(u);
    if (u >= 5) coupling.push_back(u);
  }
  std::array<double, kModeShapeUnknowns> a{};
  if (opt.staging == ModeShapeStaging::joint) {
    res.systems.push_back(equations({sc, oc}, b, all, {}, a, opt.min_cross, opt.cross_modes, lin));
    const Eigen::VectorXd x = solve(res.systems.back());
    for (int u = 0; u < n_unknowns; ++u) a[u] = x[u];
  } else {
    res.systems.push_back(
        equations({sc}, b, elastic, {}, a, opt.min_cross, opt.cross_modes, lin));  // D.1
    const Eigen::VectorXd x1 = solve(res.systems.back());
    for (int u = 0; u < 5; ++u) a[u] = x1[u];
    res.systems.push_back(
        equations({oc}, b, coupling, elastic, a, opt.min_cross, opt.cross_modes, lin));  // D.2
    const Eigen::VectorXd x2 = solve(res.systems.back());
    for (int u = 5; u < n_unknowns; ++u) a[u] = x2[u - 5];
  }
  if (lin)  // the seed's reading of the cross terms' corrections
    for (int u = 8; u < kModeShapeUnknowns; ++u) {
      const auto [k, l] = kPairs[u - 5];
      a[u] = 0.5 * (a[5 + k] + a[5 + l]);
    }
  for (const auto& eq : res.systems)
    if (eq.g.rows() == 0) {
      res.message = "mode_shape_cmcm: no usable mode pairs (all cross products below min_cross)";
      return res;
    }
  res.alpha_lifted = a;
  res.alpha = a;
  for (int n = 0; n < 5; ++n) res.c_e[n] = b.c[n] * (1.0 + a[n]);
  for (int k = 0; k < 3; ++k) res.b[k] = b.p(k, k) * (1.0 + a[5 + k]);

  // The rank-1 structure of the coupling (D.3): P_kl = s_kl √(P_kk P_ll).
  std::array<double, 8> th{};
  for (int n = 0; n < 5; ++n) th[n] = 1.0 + a[n];
  for (int k = 0; k < 3; ++k) {
    if (!(1.0 + a[5 + k] > 0)) {
      std::ostringstream s;
      s << "mode_shape_cmcm: the lifted solve gives " << mode_shape_unknown_name(5 + k)
        << " <= 0 (alpha " << a[5 + k] << "); not physical";
      res.message = s.str();
      return res;
    }
    th[5 + k] = std::sqrt(1.0 + a[5 + k]);
  }
  for (int u = 8; u < kModeShapeUnknowns; ++u) {
    const auto [k, l] = kPairs[u - 5];
    res.rank1_defect = std::max(res.rank1_defect, std::abs((1.0 + a[u]) - th[5 + k] * th[5 + l]));
  }
  auto total_residual = [&](const std::array<double, kModeShapeUnknowns>& al) {
    double s = 0;
    for (const auto& eq : res.systems) s += std::pow(residual_norm(eq, al), 2);
    return std::sqrt(s);
  };
  res.residual_lifted = total_residual(a);
  if (opt.refine_iterations > 0)
    for (const auto& eq : res.systems)
      res.refine_iterations += refine(eq, th, opt.refine_iterations, opt.svd_rel_tol);
  res.alpha = opt.refine_iterations > 0 ? alpha_of(th) : a;
  res.residual = total_residual(res.alpha);

  for (int n = 0; n < 5; ++n) res.c_e[n] = b.c[n] * (1.0 + res.alpha[n]);
  for (int k = 0; k < 3; ++k) res.b[k] = b.p(k, k) * (1.0 + res.alpha[5 + k]);
  // D.11: g_k = e_k/√εS33 carries the base's sign (y_k > 0).
  model::PiezoMaterialE u;
  u.c_e11 = res.c_e[0];
  u.c_e12 = res.c_e[1];
  u.c_e13 = res.c_e[2];
  u.c_e33 = res.c_e[3];
  u.c_e44 = res.c_e[4];
  std::array<double, 3> g{};
  for (int k = 0; k < 3; ++k) {
    const double y = opt.refine_iterations > 0 ? th[5 + k] : std::sqrt(1.0 + res.alpha[5 + k]);
    g[k] = y * b.e[k] / std::sqrt(b.eps);
  }
  u.eps_s33 = eps_s33_d11(u, g[0], g[1], targets.eps_t33);
  u.eps_s11 = 0;
  const double r = std::sqrt(u.eps_s33);
  u.e31 = g[0] * r;
  u.e33 = g[1] * r;
  u.e15 = g[2] * r;
  res.updated = u;
  try {
    model::validate(u, "mode_shape_cmcm");
  } catch (const std::invalid_argument& e) {
    res.message = std::string("mode_shape_cmcm: updated material not physical: ") + e.what();
    return res;
  }
  res.ok = true;
  return res;
}

}  // namespace piezo::update
