#include "model/modal.hpp"

#include <Eigen/SparseCholesky>
#include <Spectra/SymEigsSolver.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include "model/outer_surface_damping.hpp"
#include "model/work_counters.hpp"
#include "numerics/simd_clones.hpp"

namespace piezo::model {

namespace {

// y = (K_cond − σM)⁻¹ x on the U space, applied through the full coupled
// system [K_UU − σM, K_UΦ; K_ΦU, K_ΦΦ] [y; Φ] = [x; 0] (zero charge on every
// free potential DOF = static condensation of Φ). Factorised before use.
class CondensedShiftInvert {
 public:
  using Scalar = double;
  CondensedShiftInvert(const CoupledFactor& f, int n_u, std::span<const int> clamped)
      : f_(&f), n_u_(n_u), clamped_(clamped), rhs_(Eigen::VectorXd::Zero(f.size())) {}
  void perform_op(const Scalar* x_in, Scalar* y_out) const {
    rhs_.head(n_u_) = Eigen::Map<const Eigen::VectorXd>(x_in, n_u_);
    for (int d : clamped_) rhs_[d] = 0.0;  // the solve returns the rhs at a constrained DOF
    f_->solve(rhs_, sol_);
    Eigen::Map<Eigen::VectorXd>(y_out, n_u_) = sol_.head(n_u_);
  }

 private:
  const CoupledFactor* f_;
  int n_u_;
  std::span<const int> clamped_;
  mutable Eigen::VectorXd rhs_, sol_;
};

// Lᵀ X = Ψ for all modes at once (ModalSolver::solve), X stored transposed
// (xt: column i = DOF i's nm modes): backwards through L's columns, each
// step an AXPY over the modes — element-wise over the modes, in SIMD clones
// (numerics/simd_clones.hpp), each element's operations those of the Eigen
// column expressions this replaced (x_i −= l_qi·x_q, then x_i /= l_ii).
PIEZO_SIMD_CLONES void back_substitute_modes(double* xt, int nm, int nu, const int* outer, const int* inner,
                                             const double* val) {
  std::vector<double> acc(static_cast<std::size_t>(nm));
  double* __restrict a = acc.data();
  for (int i = nu - 1; i >= 0; --i) {
    double* xi = xt + static_cast<std::ptrdiff_t>(i) * nm;
    for (int m = 0; m < nm; ++m) a[m] = xi[m];
    // Column i of L: its diagonal first, then rows below (sorted, > i).
    for (int q = outer[i] + 1; q < outer[i + 1]; ++q) {
      const double* __restrict xq = xt + static_cast<std::ptrdiff_t>(inner[q]) * nm;
      const double l = val[q];
      for (int m = 0; m < nm; ++m) a[m] -= l * xq[m];
    }
    const double d = val[outer[i]];
    for (int m = 0; m < nm; ++m) xi[m] = a[m] / d;
  }
}

// acc_m += a_q·(x_im·x_jm) over A's entries (i, j) in its U block, x stored
// transposed (column i = DOF i's nm modes): every mode's [φ;0]ᵀA[φ;0] in one
// pass, element-wise over the modes, in SIMD clones (the Eigen expression
// this replaced: acc += a_q * x_i.cwiseProduct(x_j)).
PIEZO_SIMD_CLONES void modal_quadratic_forms(const double* xt, int nm, int nu, const int* outer, const int* inner,
                                             const double* val, double* __restrict acc) {
  for (int j = 0; j < nu; ++j) {
    const double* __restrict xj = xt + static_cast<std::ptrdiff_t>(j) * nm;
    for (int q = outer[j]; q < outer[j + 1]; ++q) {
      const int i = inner[q];
      if (i >= nu) continue;
      const double* __restrict xi = xt + static_cast<std::ptrdiff_t>(i) * nm;
      const double v = val[q];
      for (int m = 0; m < nm; ++m) acc[m] += v * (xi[m] * xj[m]);
    }
  }
}

// y = Lᵀ P (K_cond − σM)⁻¹ Pᵀ L x: the shift-invert operator in the standard
// form of K φ = λ M φ, with P M Pᵀ = L Lᵀ and ψ = Lᵀ P φ (eigenvalue
// μ = 1/(λ − σ), φ = Pᵀ L⁻ᵀ ψ). Lanczos then runs in the Euclidean inner
// product: two products with the Cholesky factor per step where the
// generalised (M-inner-product) Lanczos paid three to four products with M
// for its op, norms and re-orthogonalisation (a quarter of a port model;
// issue 43). L and Lᵀ are both stored column-major, so that each product is
// a dot product per column, four columns at a time (model/column_dots.hpp:
// four independent sums, in the lanes of an AVX2 register where there is one).
class StandardShiftInvert {
 public:
  using Scalar = double;
  StandardShiftInvert(const CondensedShiftInvert& inv, const ColumnDots& l, const ColumnDots& lt,
                      const Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int>& p,
                      const Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int>& p_inv)
      : inv_(&inv), l_(&l), lt_(&lt), p_(&p), p_inv_(&p_inv), t_(l.cols()), u_(l.cols()), w_(l.cols()) {}
  Eigen::Index rows() const { return l_->cols(); }
  Eigen::Index cols() const { return l_->cols(); }
  void perform_op(const Scalar* x_in, Scalar* y_out) const {
    lt_->apply(x_in, t_.data());            // t = L x (row i of L = column i of Lᵀ)
    u_.noalias() = *p_inv_ * t_;             // Pᵀ t
    inv_->perform_op(u_.data(), w_.data());
    t_.noalias() = *p_ * w_;                 // P w
    l_->apply(t_.data(), y_out);            // Lᵀ (P w)
  }

 private:
  const CondensedShiftInvert* inv_;
  const ColumnDots *l_, *lt_;
  const Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int>*p_, *p_inv_;
  mutable Eigen::VectorXd t_, u_, w_;
};

}  // namespace

void ModalOptions::validate() const {
  const char* fn = "ModalOptions::validate";
  if (n_modes < 1) throw std::invalid_argument(std::string(fn) + ": n_modes must be >= 1");
  if (!(shift_hz > 0)) throw std::invalid_argument(std::string(fn) + ": shift_hz must be > 0");
  if (ncv != 0 && ncv <= n_modes)
    throw std::invalid_argument(std::string(fn) + ": ncv must exceed n_modes (or be 0)");
  if (!(tolerance > 0)) throw std::invalid_argument(std::string(fn) + ": tolerance must be > 0");
  if (max_iterations < 1)
    throw std::invalid_argument(std::string(fn) + ": max_iterations must be >= 1");
  if (!(active_coupling >= 0) || !(active_coupling_open >= 0))
    throw std::invalid_argument(std::string(fn) + ": active_coupling(_open) must be >= 0");
  if (!std::isfinite(end_mass_fraction) || end_mass_fraction < 0)
    throw std::invalid_argument(std::string(fn) + ": end_mass_fraction must be finite and >= 0");
  if (!std::isfinite(outer_surface_impedance) || outer_surface_impedance < 0)
    throw std::invalid_argument(std::string(fn) +
                                ": outer_surface_impedance must be finite and >= 0");
}

const char* to_string(Symmetry s) {
  switch (s) {
    case Symmetry::symmetric: return "symmetric";
    case Symmetry::antisymmetric: return "antisymmetric";
    default: return "mixed";
  }
}

const char* to_string(Electrodes e) {
  return e == Electrodes::short_circuit ? "short_circuit" : "open_circuit";
}

std::vector<double> ModalResult::active_frequencies_hz() const {
  std::vector<double> f;
  for (const auto& m : modes)
    if (m.electrically_active) f.push_back(m.frequency_hz);
  return f;
}

void ModalSolver::check(const PiezoMaterialE& material, const char* caller) const {
  if (physical_checks_) validate(material, caller);
  else validate_finite(material, caller);
}

ModalSolver::ModalSolver(const TubeModel& model) : model_(&model), factor_(model) {
  m_uu_ = model.split().m;
}

ModalSolver::ModalSolver(const TubeModel& model, std::shared_ptr<const TubeModel> half) : ModalSolver(model) {
  if (model.extent() != TubeExtent::whole) return;
  half_tried_ = true;
  half_model_ = std::move(half);
  if (half_model_) half_solver_ = std::make_unique<ModalSolver>(*half_model_);
}

std::shared_ptr<const TubeModel> ModalSolver::half_model() {
  if (model_->extent() != TubeExtent::whole) return nullptr;
  if (!half_tried_) {
    half_tried_ = true;
    half_model_ = model_->upper_half();
    if (half_model_) half_solver_ = std::make_unique<ModalSolver>(*half_model_);
  }
  return half_model_;
}

double ModalSolver::clamped_capacitance(const PiezoMaterialE& material, Eigen::VectorXd* g) {
  check(material, "ModalSolver::clamped_capacitance");
  Eigen::VectorXd x;
  const double c0 = factor_.charge_for_unit_voltage_u_clamped(weights(material), &x);
  if (g) *g = (factor_.matrix() * x).head(model_->n_u());  // g = K_UΦ [Φ_int; 1]
  if (keep_clamped_) clamped_x_ = std::move(x);  // (own_port_vectors)
  return c0;
}

const ModalSolver::MassFactor& ModalSolver::mass_factor(double f) {
  MassFactor& mf = f == 0.0 ? m_factor_unloaded_ : m_factor_loaded_;
  if (mf.fraction != f) {
    Eigen::SimplicialLLT<SpMat, Eigen::Lower, Eigen::AMDOrdering<int>> llt(mass(f));
    if (llt.info() != Eigen::Success)
      throw std::runtime_error("ModalSolver: the mass matrix is not positive definite (its Cholesky failed)");
    mf.l = llt.matrixL();
    mf.l_dots = ColumnDots(mf.l);
    mf.lt_dots = ColumnDots(SpMat(mf.l.transpose()));
    for (Eigen::Index i = 0; i < mf.l.cols(); ++i)  // solve() reads each column's diagonal first
      if (mf.l.outerIndexPtr()[i] == mf.l.outerIndexPtr()[i + 1] || mf.l.innerIndexPtr()[mf.l.outerIndexPtr()[i]] != i)
        throw std::logic_error("ModalSolver: the mass factor's column has no leading diagonal entry");
    mf.p = llt.permutationP();
    mf.p_inv = llt.permutationPinv();
    mf.fraction = f;
  }
  return mf;
}

const SpMat& ModalSolver::mass(double f) {
  if (f == 0.0) return m_uu_;
  if (f != m_loaded_fraction_) {
    m_loaded_ = model_->mass(f);
    m_loaded_fraction_ = f;
  }
  return m_loaded_;
}

double ModalSolver::static_capacitance(const PiezoMaterialE& material,
                                       Eigen::VectorXd* u_static) {
  check(material, "ModalSolver::static_capacitance");
  return static_solve(material, m_uu_, u_static);
}

double ModalSolver::static_solve(const PiezoMaterialE& material, const SpMat& mass,
                                 Eigen::VectorXd* u_static) {
  // The only zero-energy mode of the free tube is the rigid axial translation;
  // fixing one u_z removes it without loading the tube (the electric load is
  // self-equilibrated), so Q is that of the free tube.
  const int fix_rigid[1] = {model_->dofs().u_z(0)};
  const bool half = model_->extent() == TubeExtent::upper_half;  // no rigid mode: u_z = 0 at the mid-plane
  const std::span<const int> fix = half ? std::span<const int>(model_->symmetry_plane_dofs())
                                        : std::span<const int>(fix_rigid);
  Eigen::VectorXd x;
  const double c = factor_.charge_for_unit_voltage(weights(material), fix, &x);
  if (u_static && half) {
    *u_static = x.head(model_->n_u());
  } else if (u_static) {
    Eigen::VectorXd u = x.head(model_->n_u());
    Eigen::VectorXd rigid = Eigen::VectorXd::Zero(model_->n_u());
    for (int n = 0; n < model_->mesh().num_nodes(); ++n) rigid[model_->dofs().u_z(n)] = 1.0;
    const Eigen::VectorXd mr = mass * rigid;
    u -= (mr.dot(u) / mr.dot(rigid)) * rigid;  // M-orthogonal to the rigid mode
    *u_static = std::move(u);
  }
  return c;
}

ModalResult ModalSolver::solve(const PiezoMaterialE& material, Electrodes electrodes,
                               const ModalOptions& opt) {
  check(material, "ModalSolver::solve");
  opt.validate();
  g_modal_solves.fetch_add(1, std::memory_order_relaxed);  // model/work_counters.hpp
  const int nu = model_->n_u();
  if (opt.n_modes >= nu) throw std::invalid_argument("ModalSolver::solve: n_modes >= n_u");
  ModalResult res;
  res.electrodes = electrodes;
  res.end_mass_fraction = opt.end_mass_fraction;
  const auto w = weights(material);
  const SpMat& m_uu = mass(opt.end_mass_fraction);

  Eigen::VectorXd g;
  res.c_clamped = clamped_capacitance(material, &g);

  const std::vector<int>& plane = model_->symmetry_plane_dofs();  // empty for the whole tube
  // The whole tube's rigid axial translation needs a shift below it; the
  // half (u_z = 0 on the mid-plane) has no rigid mode, so K itself is
  // factorised (σ = 0): the static solve's factor, which a port model has
  // just made (CoupledFactor keeps it). The shift's size against the first
  // mode's λ (1 kHz against tens of kHz) hardly changes the Lanczos run.
  const double sigma = plane.empty() ? -std::pow(2.0 * M_PI * opt.shift_hz, 2) : 0.0;
  if (!factor_.factorize(w, sigma, electrodes, plane, opt.end_mass_fraction)) {
    res.message = "singular shifted system";
    return res;
  }
  CondensedShiftInvert inv(factor_, nu, plane);
  const MassFactor& mf = mass_factor(opt.end_mass_fraction);
  StandardShiftInvert op(inv, mf.l_dots, mf.lt_dots, mf.p, mf.p_inv);
  const int ncv = std::min<int>(nu, opt.ncv > 0 ? opt.ncv : std::max(2 * opt.n_modes + 1, opt.n_modes + 20));
  Spectra::SymEigsSolver<StandardShiftInvert> eigs(op, opt.n_modes, ncv);
  eigs.init();
  res.n_converged = static_cast<int>(
      eigs.compute(Spectra::SortRule::LargestMagn, opt.max_iterations, opt.tolerance));
  res.converged = eigs.info() == Spectra::CompInfo::Successful;
  if (!res.converged) {
    res.message = "Lanczos did not converge: " + std::to_string(res.n_converged) + " of " +
                  std::to_string(opt.n_modes) + " modes";
    if (res.n_converged == 0) return res;
  }
  // μ = 1/(λ − σ) → λ; ψ → φ = Pᵀ L⁻ᵀ ψ (M(f)-orthonormal).
  const Eigen::VectorXd lambda = (sigma + eigs.eigenvalues().array().inverse()).matrix();
  Eigen::MatrixXd vecs = eigs.eigenvectors();
  {
    // Lᵀ X = Ψ for all modes at once, backwards through L's columns, each
    // step an AXPY over the modes (X stored transposed: a DOF's modes
    // contiguous) instead of one sparse triangular solve per mode.
    Eigen::MatrixXd xt = vecs.transpose();
    const int* outer = mf.l.outerIndexPtr();
    const int* inner = mf.l.innerIndexPtr();
    const double* val = mf.l.valuePtr();
    back_substitute_modes(xt.data(), static_cast<int>(xt.rows()), nu, outer, inner, val);
    vecs = mf.p_inv * xt.transpose();
  }
  std::vector<int> order(lambda.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return lambda[a] < lambda[b]; });

  // The shapes, M(f)-normalised by the transform (φ = Pᵀ L⁻ᵀ ψ, ψ orthonormal),
  // ascending; sign convention: largest |u_r| component positive (reproducible shapes).
  res.shapes.resize(nu, static_cast<Eigen::Index>(order.size()));
  for (std::size_t j = 0; j < order.size(); ++j) {
    auto phi = res.shapes.col(static_cast<Eigen::Index>(j));
    phi = vecs.col(order[j]);
    Eigen::Index imax;
    phi.cwiseAbs().maxCoeff(&imax);
    if (phi[imax] < 0) phi = -phi;
  }
  // κ_k = φᵀK_UUφ without assembling K_UU: the factorised matrix's U block is
  // K_UU − σ·M(f), and φ is M(f)-normalised, so κ = [φ;0]ᵀA[φ;0] + σ — all
  // modes' products in one pass over A's U columns.
  const SpMat& a_shifted = factor_.matrix();
  Eigen::VectorXd kappa = Eigen::VectorXd::Constant(res.shapes.cols(), sigma);
  {
    const Eigen::MatrixXd st = res.shapes.transpose();  // a DOF's modes contiguous
    const int* outer = a_shifted.outerIndexPtr();
    const int* inner = a_shifted.innerIndexPtr();
    const double* val = a_shifted.valuePtr();
    Eigen::VectorXd acc = Eigen::VectorXd::Zero(res.shapes.cols());
    modal_quadratic_forms(st.data(), static_cast<int>(st.rows()), nu, outer, inner, val, acc.data());
    kappa += acc;
  }

  const double rigid_omega = 2.0 * M_PI * 1e-3 * opt.shift_hz;
  for (std::size_t j = 0; j < order.size(); ++j) {
    const auto phi = res.shapes.col(static_cast<Eigen::Index>(j));
    Mode m;
    m.eigenvalue = lambda[order[j]];
    m.omega = std::sqrt(std::max(m.eigenvalue, 0.0));
    m.frequency_hz = m.omega / (2.0 * M_PI);
    if (plane.empty()) {
      const Eigen::VectorXd sym = 0.5 * (phi + model_->mirror(phi));
      m.symmetric_fraction = sym.dot(m_uu * sym);
    } else {
      m.symmetric_fraction = 1.0;  // the half with u_z = 0 on the mid-plane has only symmetric modes
    }
    m.symmetry = m.symmetric_fraction > 0.99   ? Symmetry::symmetric
                 : m.symmetric_fraction < 0.01 ? Symmetry::antisymmetric
                                               : Symmetry::mixed;
    m.participation = g.dot(phi);
    m.kappa = kappa[static_cast<Eigen::Index>(j)];
    if (m.omega > rigid_omega)
      m.coupling = m.participation * m.participation / (m.omega * m.omega * res.c_clamped);
    const double threshold =
        electrodes == Electrodes::open_circuit ? opt.active_coupling_open : opt.active_coupling;
    m.electrically_active = m.symmetric_fraction > 0.5 && m.coupling > threshold;
    res.modes.push_back(m);
  }
  return res;
}

ModalPortModel ModalSolver::half_port_model(const PiezoMaterialE& material, const ModalOptions& opt) {
  ModalOptions ho = opt;
  ho.n_modes = opt.n_modes / 2 + 1;
  ho.ncv = opt.ncv > 0 ? std::max(ho.n_modes + 1, opt.ncv / 2) : 0;
  ModalPortModel p = half_solver_->port_model(material, ho);
  half_to_whole(p);
  return p;
}

ModalPortModel ModalSolver::port_model(const PiezoMaterialE& material, const ModalOptions& opt,
                                       ModalResult* sc_result) {
  // (A model with its shapes, sc_result, is solved: the memo keeps port models only.)
  if (sc_result || !memo_ || memo_->tube() != model_) return solve_port_model(material, opt, sc_result);
  if (auto p = memo_->find(material, opt, physical_checks_, memo_reader_)) return std::move(*p);
  ModalPortModel p = solve_port_model(material, opt, nullptr);  // (throws as it did: nothing remembered)
  memo_->insert(material, opt, physical_checks_, p, memo_reader_);
  return p;
}

ModalPortModel ModalSolver::solve_port_model(const PiezoMaterialE& material, const ModalOptions& opt,
                                             ModalResult* sc_result) {
  if (opt.mirror_symmetry && !sc_result && model_->extent() == TubeExtent::whole) {
    half_model();  // built on the first port model
    if (half_solver_) {
      check(material, "ModalSolver::port_model");
      half_solver_->physical_checks_ = physical_checks_;
      opt.validate();
      return half_port_model(material, opt);
    }
  }
  // The static solve first: the short-circuit solve's clamped capacitance
  // then finds the same σ = 0 matrix combined (CoupledFactor::combine). The
  // solve's own checks before it, so that bad input fails as it did.
  check(material, "ModalSolver::solve");
  opt.validate();
  const SpMat& m_uu = mass(opt.end_mass_fraction);
  Eigen::VectorXd us;
  const double c_static = static_solve(material, m_uu, &us);
  ModalResult sc = solve(material, Electrodes::short_circuit, opt);
  ModalPortModel p;
  p.converged = sc.converged;
  p.c_clamped = sc.c_clamped;
  p.end_mass_fraction = opt.end_mass_fraction;
  if (material.eps_s33 > 0) p.eps_t_over_s = to_d_form(material).eps_t33 / material.eps_s33;
  p.c_static = c_static;
  const double rigid_omega = 2.0 * M_PI * 1e-3 * opt.shift_hz;
  for (std::size_t j = 0; j < sc.modes.size(); ++j) {
    const Mode& m = sc.modes[j];
    if (m.omega <= rigid_omega) continue;  // rigid translation: p = 0 exactly
    p.modes.push_back({m.omega, m.participation, m.kappa, m.symmetry == Symmetry::symmetric});
    if (opt.outer_surface_impedance > 0)  // c_k += Z_a·φ_kᵀC_a1φ_k (outer_surface_damping.hpp)
      p.modes.back().radiation_damping =
          opt.outer_surface_impedance *
          outer_surface_modal_damping(model_->mesh(), model_->dofs(),
                                      sc.shapes.col(static_cast<Eigen::Index>(j)));
  }
  // Residual pseudo-mode from the two moments of the truncated modes (port_model.hpp).
  add_residual_mode(p, us.dot(m_uu * us));
  if (sc_result) *sc_result = std::move(sc);
  return p;
}

std::optional<PortVectors> ModalSolver::port_vectors(const PiezoMaterialE& material,
                                                     const ModalOptions& opt) {
  if (!opt.mirror_symmetry || opt.outer_surface_impedance > 0 || model_->extent() != TubeExtent::whole)
    return std::nullopt;
  half_model();
  if (!half_solver_) return std::nullopt;
  check(material, "ModalSolver::port_vectors");
  half_solver_->physical_checks_ = physical_checks_;
  opt.validate();
  ModalOptions ho = opt;  // as half_port_model
  ho.n_modes = opt.n_modes / 2 + 1;
  ho.ncv = opt.ncv > 0 ? std::max(ho.n_modes + 1, opt.ncv / 2) : 0;
  auto v = half_solver_->own_port_vectors(material, ho);
  if (v) {
    v->model = half_model_;
    v->end_mass_fraction = opt.end_mass_fraction;
  }
  return v;
}

std::optional<PortVectors> ModalSolver::own_port_vectors(const PiezoMaterialE& material,
                                                         const ModalOptions& opt) {
  keep_clamped_ = true;  // (solve's clamped solution: the clamped potentials below)
  ModalResult sc;
  try {
    sc = solve(material, Electrodes::short_circuit, opt);
  } catch (...) {
    keep_clamped_ = false;
    throw;
  }
  keep_clamped_ = false;
  if (!sc.converged) return std::nullopt;
  const int nu = model_->n_u(), nt = model_->dofs().n_total(), np = nt - nu - 1;
  const std::vector<int>& plane = model_->symmetry_plane_dofs();
  const auto k = static_cast<Eigen::Index>(sc.modes.size());
  PortVectors v;
  v.u.resize(nu, k + 1);
  v.phi.resize(np, k + 2);
  // The factor holds K − σM(f) of the Lanczos run: (K − σM)[y; Φ] = [Mφ; 0]
  // gives y = φ/(ω² − σ) and the interior potentials Φ that go with it.
  const SpMat& m_uu = mass(opt.end_mass_fraction);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(nt), y;
  for (Eigen::Index j = 0; j < k; ++j) {
    Eigen::VectorXd phi = sc.shapes.col(j);
    for (int d : plane) phi[d] = 0.0;  // (a Lanczos vector keeps a trace of the start there)
    v.u.col(j) = phi;
    rhs.head(nu) = m_uu * phi;
    for (int d : plane) rhs[d] = 0.0;
    factor_.solve(rhs, y);
    v.phi.col(j) = y.segment(nu, np);
  }
  const auto w = weights(material);
  Eigen::VectorXd x;
  factor_.charge_for_unit_voltage(w, plane, &x);  // static: U free but the mid-plane's u_z
  v.u.col(k) = x.head(nu);
  v.phi.col(k) = x.segment(nu, np);
  v.phi.col(k + 1) = clamped_x_.segment(nu, np);  // clamped
  return v;
}

}  // namespace piezo::model
