#include "model/modal.hpp"

#include <Spectra/SymGEigsShiftSolver.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include "model/outer_surface_damping.hpp"
#include "model/work_counters.hpp"

namespace piezo::model {

namespace {

// y = (K_cond − σM)⁻¹ x on the U space, applied through the full coupled
// system [K_UU − σM, K_UΦ; K_ΦU, K_ΦΦ] [y; Φ] = [x; 0] (zero charge on every
// free potential DOF = static condensation of Φ). Factorised before use.
class CondensedShiftInvert {
 public:
  using Scalar = double;
  CondensedShiftInvert(const CoupledFactor& f, int n_u, double sigma, std::span<const int> clamped)
      : f_(&f), n_u_(n_u), sigma_(sigma), clamped_(clamped), rhs_(Eigen::VectorXd::Zero(f.size())) {}
  Eigen::Index rows() const { return n_u_; }
  Eigen::Index cols() const { return n_u_; }
  void set_shift(const Scalar& sigma) {
    if (sigma != sigma_)
      throw std::logic_error("CondensedShiftInvert: factorised for a different shift");
  }
  void perform_op(const Scalar* x_in, Scalar* y_out) const {
    rhs_.head(n_u_) = Eigen::Map<const Eigen::VectorXd>(x_in, n_u_);
    for (int d : clamped_) rhs_[d] = 0.0;  // the solve returns the rhs at a constrained DOF
    f_->solve(rhs_, sol_);
    Eigen::Map<Eigen::VectorXd>(y_out, n_u_) = sol_.head(n_u_);
  }

 private:
  const CoupledFactor* f_;
  int n_u_;
  double sigma_;
  std::span<const int> clamped_;
  mutable Eigen::VectorXd rhs_, sol_;
};

// B-product x ↦ M x for Spectra with M symmetric and stored with both
// triangles (SplitSystem's pattern): column j of M is also its row j, so
// y_j = M(:, j)·x is one gather per column. Spectra's SparseSymMatProd goes
// through selfadjointView, which scatters into y and was a quarter of a port
// model's time (perf, single-shot diagnosis bench).
//
// Spectra's Lanczos step asks for B·f twice in a row for the same residual f
// (its B-norm, then Vᵀ·B·f for the re-orthogonalisation test, and again
// after each correction): the last product is kept and returned when the
// input is the same vector, one comparison instead of a sparse product
// (a third of the B-products of a port model).
class SymmetricStoredProd {
 public:
  using Scalar = double;
  explicit SymmetricStoredProd(const SpMat& m)
      : m_(&m), last_in_(Eigen::VectorXd::Constant(m.cols(), NAN)), last_out_(m.cols()) {}
  Eigen::Index rows() const { return m_->rows(); }
  Eigen::Index cols() const { return m_->cols(); }
  void perform_op(const Scalar* x_in, Scalar* y_out) const {
    const Eigen::Index n = m_->cols();
    if (std::equal(x_in, x_in + n, last_in_.data())) {  // (NaN at first: never equal)
      std::copy(last_out_.data(), last_out_.data() + n, y_out);
      return;
    }
    const int* outer = m_->outerIndexPtr();
    const int* inner = m_->innerIndexPtr();
    const double* val = m_->valuePtr();
    // Four columns at a time: four independent sums the CPU overlaps, where one
    // column's sum waits on its previous add at every term (the product was a
    // sixth of a replay's time, latency-bound). Each sum still runs over its
    // column in storage order, so the product is bit-identical to one column
    // at a time (no FMA contraction on our x86-64 baseline; issue 43).
    Eigen::Index j = 0;
    for (; j + 4 <= n; j += 4) {
      const int b0 = outer[j], b1 = outer[j + 1], b2 = outer[j + 2], b3 = outer[j + 3], e3 = outer[j + 4];
      const int common = std::min({b1 - b0, b2 - b1, b3 - b2, e3 - b3});
      double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
      for (int t = 0; t < common; ++t) {
        s0 += val[b0 + t] * x_in[inner[b0 + t]];
        s1 += val[b1 + t] * x_in[inner[b1 + t]];
        s2 += val[b2 + t] * x_in[inner[b2 + t]];
        s3 += val[b3 + t] * x_in[inner[b3 + t]];
      }
      for (int p = b0 + common; p < b1; ++p) s0 += val[p] * x_in[inner[p]];
      for (int p = b1 + common; p < b2; ++p) s1 += val[p] * x_in[inner[p]];
      for (int p = b2 + common; p < b3; ++p) s2 += val[p] * x_in[inner[p]];
      for (int p = b3 + common; p < e3; ++p) s3 += val[p] * x_in[inner[p]];
      y_out[j] = s0;
      y_out[j + 1] = s1;
      y_out[j + 2] = s2;
      y_out[j + 3] = s3;
    }
    for (; j < n; ++j) {
      double s = 0.0;
      for (int p = outer[j]; p < outer[j + 1]; ++p) s += val[p] * x_in[inner[p]];
      y_out[j] = s;
    }
    std::copy(x_in, x_in + n, last_in_.data());
    std::copy(y_out, y_out + n, last_out_.data());
  }
  Eigen::MatrixXd operator*(const Eigen::Ref<const Eigen::MatrixXd>& x) const {
    Eigen::MatrixXd y(rows(), x.cols());
    for (Eigen::Index c = 0; c < x.cols(); ++c) perform_op(x.col(c).data(), y.col(c).data());
    return y;
  }
  Scalar operator()(Eigen::Index i, Eigen::Index j) const { return m_->coeff(i, j); }

 private:
  const SpMat* m_;
  mutable Eigen::VectorXd last_in_, last_out_;
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
  all_u_.resize(model.n_u());
  std::iota(all_u_.begin(), all_u_.end(), 0);
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
  const double c0 = factor_.charge_for_unit_voltage(weights(material), all_u_, &x);
  if (g) *g = (factor_.matrix() * x).head(model_->n_u());  // g = K_UΦ [Φ_int; 1]
  if (keep_clamped_) clamped_x_ = std::move(x);  // (own_port_vectors)
  return c0;
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

  const double sigma = -std::pow(2.0 * M_PI * opt.shift_hz, 2);
  const std::vector<int>& plane = model_->symmetry_plane_dofs();  // empty for the whole tube
  if (!factor_.factorize(w, sigma, electrodes, plane, opt.end_mass_fraction)) {
    res.message = "singular shifted system";
    return res;
  }
  CondensedShiftInvert op(factor_, nu, sigma, plane);
  SymmetricStoredProd bop(m_uu);
  const int ncv = std::min<int>(nu, opt.ncv > 0 ? opt.ncv : std::max(2 * opt.n_modes + 1, opt.n_modes + 20));
  Spectra::SymGEigsShiftSolver<CondensedShiftInvert, SymmetricStoredProd,
                               Spectra::GEigsMode::ShiftInvert>
      eigs(op, bop, opt.n_modes, ncv, sigma);
  eigs.init();
  res.n_converged = static_cast<int>(
      eigs.compute(Spectra::SortRule::LargestMagn, opt.max_iterations, opt.tolerance));
  res.converged = eigs.info() == Spectra::CompInfo::Successful;
  if (!res.converged) {
    res.message = "Lanczos did not converge: " + std::to_string(res.n_converged) + " of " +
                  std::to_string(opt.n_modes) + " modes";
    if (res.n_converged == 0) return res;
  }
  const Eigen::VectorXd lambda = eigs.eigenvalues();
  const Eigen::MatrixXd vecs = eigs.eigenvectors();
  std::vector<int> order(lambda.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return lambda[a] < lambda[b]; });

  // κ_k = φᵀK_UUφ without assembling K_UU: the factorised matrix's U block is
  // K_UU − σ·M(f), and φ is M(f)-normalised, so κ = [φ;0]ᵀA[φ;0] + σ.
  const SpMat& a_shifted = factor_.matrix();
  Eigen::VectorXd phi_full = Eigen::VectorXd::Zero(a_shifted.rows());

  res.shapes.resize(nu, static_cast<Eigen::Index>(order.size()));
  const double rigid_omega = 2.0 * M_PI * 1e-3 * opt.shift_hz;
  for (std::size_t j = 0; j < order.size(); ++j) {
    Eigen::VectorXd phi = vecs.col(order[j]);
    const double mnorm = std::sqrt(phi.dot(m_uu * phi));
    phi /= mnorm;
    // Sign convention: largest |u_r| component positive (reproducible shapes).
    Eigen::Index imax;
    phi.cwiseAbs().maxCoeff(&imax);
    if (phi[imax] < 0) phi = -phi;
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
    phi_full.head(nu) = phi;
    m.kappa = phi_full.dot(a_shifted * phi_full) + sigma;
    if (m.omega > rigid_omega)
      m.coupling = m.participation * m.participation / (m.omega * m.omega * res.c_clamped);
    const double threshold =
        electrodes == Electrodes::open_circuit ? opt.active_coupling_open : opt.active_coupling;
    m.electrically_active = m.symmetric_fraction > 0.5 && m.coupling > threshold;
    res.shapes.col(static_cast<Eigen::Index>(j)) = phi;
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
  if (opt.mirror_symmetry && !sc_result && model_->extent() == TubeExtent::whole) {
    half_model();  // built on the first port model
    if (half_solver_) {
      check(material, "ModalSolver::port_model");
      half_solver_->physical_checks_ = physical_checks_;
      opt.validate();
      return half_port_model(material, opt);
    }
  }
  ModalResult sc = solve(material, Electrodes::short_circuit, opt);
  ModalPortModel p;
  p.converged = sc.converged;
  p.c_clamped = sc.c_clamped;
  p.end_mass_fraction = opt.end_mass_fraction;
  if (material.eps_s33 > 0) p.eps_t_over_s = to_d_form(material).eps_t33 / material.eps_s33;
  const SpMat& m_uu = mass(opt.end_mass_fraction);
  Eigen::VectorXd us;
  p.c_static = static_solve(material, m_uu, &us);
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
