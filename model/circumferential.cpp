#include "model/circumferential.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>

#include <Spectra/MatOp/DenseSymMatProd.h>
#include <Spectra/MatOp/SymShiftInvert.h>
#include <Spectra/SymGEigsShiftSolver.h>

#include "model/element.hpp"

namespace piezo::model {

namespace {

constexpr int kComp = 4;  // per node: U_r, U_θ, U_z, Φ
enum Comp { ur = 0, ut = 1, uz = 2, ph = 3 };

[[noreturn]] void fail(const std::string& what) {
  throw std::invalid_argument("circumferential_modes: " + what);
}

// Where each (node, component) goes: ≥ 0 an index into the displacement block
// (for U) or the condensed potential block (for Φ); −1 fixed at zero. Several
// outer-surface potentials share one index for n = 0 in open circuit (V).
struct Numbering {
  std::vector<int> index;  // node·kComp + comp
  int n_u = 0, n_phi = 0;
  int electrode = -1;      // potential index of V (n = 0, open circuit), else −1
};

Numbering number(const TubeMesh& mesh, const CircumferentialOptions& o) {
  const bool n0 = o.n == 0;
  const bool cos_family = o.family == HarmonicFamily::cos_family;
  Numbering nb;
  nb.index.assign(static_cast<std::size_t>(mesh.num_nodes() * kComp), -1);
  // Displacements.
  for (int node = 0; node < mesh.num_nodes(); ++node)
    for (int c : {ur, ut, uz}) {
      bool used = true;
      if (n0) used = cos_family ? c != ut : c == ut;  // the weightless group is removed
      if (c == uz && o.axial_constrained) used = false;
      if (used) nb.index[static_cast<std::size_t>(node * kComp + c)] = nb.n_u++;
    }
  // Potentials (group A): none in the n = 0 sin family (torsion).
  if (n0 && !cos_family) return nb;
  const bool open_v = n0 && o.electrodes == Electrodes::open_circuit;
  for (int node = 0; node < mesh.num_nodes(); ++node) {
    if (mesh.on_inner_surface(node)) continue;  // grounded electrode
    if (mesh.on_outer_surface(node)) {
      if (!open_v) continue;  // short circuit, or n ≥ 1 (no harmonic on an equipotential)
      if (nb.electrode < 0) nb.electrode = nb.n_phi++;
      nb.index[static_cast<std::size_t>(node * kComp + ph)] = nb.electrode;
      continue;
    }
    nb.index[static_cast<std::size_t>(node * kComp + ph)] = nb.n_phi++;
  }
  return nb;
}

// The uncondensed blocks, dense, in the numbering above; b is the coupling to
// the outer electrode at V = 1 (its column of K_UΦ, K_ΦΦ) for n = 0 cos in
// short circuit, where V is prescribed.
struct Blocks {
  Eigen::MatrixXd m, k_uu, k_up, k_pp;
  Eigen::VectorXd b_u, b_p;  // K_U,V and K_Φint,V
  double k_vv = 0;           // K_VV
};

Blocks assemble(const TubeMesh& mesh, const Numbering& nb, const TubeGeometry& g,
                const PiezoMaterialE& material, const CircumferentialOptions& o) {
  const PiezoMatrices pm = to_matrices(material);  // full 6×6 cE, 3×6 e, 3×3 εS, IEEE axes
  const Eigen::Matrix<double, 6, 6>& c = pm.elastic;
  const Eigen::Matrix<double, 3, 6>& e = pm.piezo;
  const Eigen::Matrix3d& eps = pm.dielectric;
  const bool n0 = o.n == 0;
  const double s = o.family == HarmonicFamily::cos_family ? 1.0 : -1.0;
  const double m = s * o.n;
  // θ-integrals of the squared trig factor of each group (see the header).
  const double w_cos = n0 ? 2.0 * M_PI : M_PI, w_sin = n0 ? 0.0 : M_PI;
  const double wa = s > 0 ? w_cos : w_sin, wb = s > 0 ? w_sin : w_cos;
  const Eigen::Matrix<double, 6, 1> ws = (Eigen::Matrix<double, 6, 1>() << wa, wa, wa, wb, wa, wb).finished();
  const Eigen::Vector3d we(wa, wb, wa);
  const Eigen::Matrix<double, 6, 6> cw = c * ws.asDiagonal();   // c couples no A with B: = diag·c
  const Eigen::Matrix<double, 6, 3> ew = e.transpose() * we.asDiagonal();
  const Eigen::Matrix3d epsw = eps * we.asDiagonal();

  Blocks bl;
  bl.m = Eigen::MatrixXd::Zero(nb.n_u, nb.n_u);
  bl.k_uu = Eigen::MatrixXd::Zero(nb.n_u, nb.n_u);
  bl.k_up = Eigen::MatrixXd::Zero(nb.n_u, nb.n_phi);
  bl.k_pp = Eigen::MatrixXd::Zero(nb.n_phi, nb.n_phi);
  bl.b_u = Eigen::VectorXd::Zero(nb.n_u);
  bl.b_p = Eigen::VectorXd::Zero(nb.n_phi);
  const bool v_prescribed = n0 && o.family == HarmonicFamily::cos_family && nb.electrode < 0;

  const GaussRule gr = gauss_legendre(o.gauss_points);
  Eigen::Matrix<double, 6, 27> bu;  // local u: node a → 3a + {r, θ, z}
  Eigen::Matrix<double, 3, 9> bp;
  Eigen::Matrix<double, 3, 27> nu;
  Eigen::Matrix<double, 27, 27> km, kk;
  Eigen::Matrix<double, 27, 9> kup;
  Eigen::Matrix<double, 9, 9> kpp;
  for (int el = 0; el < mesh.num_elements(); ++el) {
    const auto& conn = mesh.element(el);
    std::array<Node, kElemNodes> x;
    for (int a = 0; a < kElemNodes; ++a) x[static_cast<std::size_t>(a)] = mesh.nodes()[static_cast<std::size_t>(conn[a])];
    km.setZero();
    kk.setZero();
    kup.setZero();
    kpp.setZero();
    for (int qz = 0; qz < gr.n; ++qz)
      for (int qr = 0; qr < gr.n; ++qr) {
        const Q2Point q = q2_point(x, gr.x[qr], gr.x[qz]);
        const double r = q.r, det = q.det;
        const auto& n = q.n;
        if (!(det > 0) || !(r > 0)) fail("degenerate or inverted element " + std::to_string(el));
        const double dv = r * det * gr.w[qr] * gr.w[qz];  // the θ-weight is in cw, ew, epsw
        bu.setZero();
        bp.setZero();
        nu.setZero();
        for (int a = 0; a < 9; ++a) {
          const double dr = q.dr[a], dz = q.dz[a];
          const int r_ = 3 * a, t_ = 3 * a + 1, z_ = 3 * a + 2;
          bu(0, z_) = dz;              // S1 = ∂U_z/∂z
          bu(1, r_) = n[a] / r;        // S2 = (U_r + m U_θ)/r
          bu(1, t_) = m * n[a] / r;
          bu(2, r_) = dr;              // S3 = ∂U_r/∂r
          bu(3, r_) = -m * n[a] / r;   // S4 = −m U_r/r + ∂U_θ/∂r − U_θ/r
          bu(3, t_) = dr - n[a] / r;
          bu(4, r_) = dz;              // S5 = ∂U_r/∂z + ∂U_z/∂r
          bu(4, z_) = dr;
          bu(5, t_) = dz;              // S6 = ∂U_θ/∂z − m U_z/r
          bu(5, z_) = -m * n[a] / r;
          bp(0, a) = dz;               // −E1
          bp(1, a) = -m * n[a] / r;    // −E2
          bp(2, a) = dr;               // −E3
          nu(0, r_) = nu(1, t_) = nu(2, z_) = n[a];
        }
        const Eigen::Vector3d wm(wa, wb, wa);  // u_r, u_z in group A, u_θ in B
        kk.noalias() += dv * bu.transpose() * cw * bu;
        kup.noalias() += dv * bu.transpose() * ew * bp;
        kpp.noalias() -= dv * bp.transpose() * epsw * bp;  // seed sign, eq. 76
        km.noalias() += dv * g.density_kg_m3 * nu.transpose() * wm.asDiagonal() * nu;
      }
    // Scatter.
    auto uidx = [&](int la) {  // local u DOF → global or −1
      const int node = conn[la / 3];
      const int comp = la % 3 == 0 ? ur : la % 3 == 1 ? ut : uz;
      return nb.index[static_cast<std::size_t>(node * kComp + comp)];
    };
    auto pidx = [&](int a) { return nb.index[static_cast<std::size_t>(conn[a] * kComp + ph)]; };
    auto is_v = [&](int a) { return v_prescribed && mesh.on_outer_surface(conn[a]); };
    for (int i = 0; i < 27; ++i) {
      const int gi = uidx(i);
      if (gi < 0) continue;
      for (int j = 0; j < 27; ++j) {
        const int gj = uidx(j);
        if (gj < 0) continue;
        bl.k_uu(gi, gj) += kk(i, j);
        bl.m(gi, gj) += km(i, j);
      }
      for (int a = 0; a < 9; ++a) {
        const int pa = pidx(a);
        if (pa >= 0) bl.k_up(gi, pa) += kup(i, a);
        if (is_v(a)) bl.b_u[gi] += kup(i, a);
      }
    }
    for (int a = 0; a < 9; ++a) {
      const int pa = pidx(a);
      for (int b2 = 0; b2 < 9; ++b2) {
        const int pb = pidx(b2);
        if (pa >= 0 && pb >= 0) bl.k_pp(pa, pb) += kpp(a, b2);
        if (pa >= 0 && is_v(b2)) bl.b_p[pa] += kpp(a, b2);
        if (is_v(a) && is_v(b2)) bl.k_vv += kpp(a, b2);
      }
    }
  }
  return bl;
}

// The modes up to f_max by shift-invert Lanczos (σ below the rigid motions,
// so K − σM is positive definite), growing the count until one lies above
// f_max. False: not asked for, too small, or not converged (→ dense).
bool lanczos(const Eigen::MatrixXd& k, const Eigen::MatrixXd& m, double f_max, Eigen::VectorXd& lam,
             Eigen::MatrixXd& vec) {
  const Eigen::Index n = k.rows();
  if (!(f_max > 0) || n < 200) return false;
  const double sigma = -std::pow(2.0 * M_PI * 1000.0, 2);
  const double lam_max = std::pow(2.0 * M_PI * f_max, 2);
  using Op = Spectra::SymShiftInvert<double, Eigen::Dense, Eigen::Dense>;
  using BOp = Spectra::DenseSymMatProd<double>;
  Op op(k, m);
  BOp bop(m);
  for (Eigen::Index nev = 16; nev < n / 2; nev *= 2) {
    const Eigen::Index ncv = std::min<Eigen::Index>(n, 2 * nev + 1);
    Spectra::SymGEigsShiftSolver<Op, BOp, Spectra::GEigsMode::ShiftInvert> eigs(op, bop, nev, ncv, sigma);
    eigs.init();
    eigs.compute(Spectra::SortRule::LargestMagn, 1000, 1e-10);
    if (eigs.info() != Spectra::CompInfo::Successful) return false;
    const Eigen::VectorXd l = eigs.eigenvalues();
    if (l.maxCoeff() > lam_max) {
      std::vector<Eigen::Index> order(static_cast<std::size_t>(l.size()));
      std::iota(order.begin(), order.end(), Eigen::Index{0});
      std::sort(order.begin(), order.end(), [&](Eigen::Index a, Eigen::Index b) { return l[a] < l[b]; });
      const Eigen::MatrixXd v = eigs.eigenvectors();
      Eigen::Index keep = 0;  // those up to f_max and the first above it
      while (keep < l.size() && l[order[static_cast<std::size_t>(keep)]] <= lam_max) ++keep;
      keep = std::min<Eigen::Index>(keep + 1, l.size());
      lam.resize(keep);
      vec.resize(n, keep);
      for (Eigen::Index j = 0; j < keep; ++j) {
        lam[j] = l[order[static_cast<std::size_t>(j)]];
        vec.col(j) = v.col(order[static_cast<std::size_t>(j)]);
      }
      return true;
    }
  }
  return false;
}

}  // namespace

const char* to_string(HarmonicFamily f) {
  return f == HarmonicFamily::cos_family ? "cos" : "sin";
}

void CircumferentialOptions::validate() const {
  if (n < 0 || n > 64) fail("harmonic n must lie in 0 … 64, got " + std::to_string(n));
  if (gauss_points < 2 || gauss_points > 4) fail("gauss_points must be 2 … 4");
  if (!(max_frequency_hz >= 0) || !std::isfinite(max_frequency_hz)) fail("max_frequency_hz must be finite and >= 0");
  mesh.validate();
}

double torsion_frequency_hz(const TubeGeometry& g, const PiezoMaterialE& m, int k) {
  g.validate();
  const double c66 = 0.5 * (m.c_e11 - m.c_e12);
  if (!(c66 > 0) || k < 1) throw std::invalid_argument("torsion_frequency_hz: need cE11 > cE12 and k >= 1");
  return k / (2.0 * g.length_m) * std::sqrt(c66 / g.density_kg_m3);
}

CircumferentialResult circumferential_modes(const TubeGeometry& geometry, const PiezoMaterialE& material,
                                            const CircumferentialOptions& options, bool keep_shapes) {
  geometry.validate();
  options.validate();
  validate(material, "circumferential_modes");
  const TubeMesh mesh(geometry, options.mesh);
  const Numbering nb = number(mesh, options);
  if (nb.n_u + nb.n_phi > kMaxDenseDofs)
    fail("the mesh has " + std::to_string(nb.n_u + nb.n_phi) + " DOFs for harmonic " +
         std::to_string(options.n) + ", above the dense limit of " + std::to_string(kMaxDenseDofs) +
         "; use a coarser mesh (--nr/--nz)");
  Blocks bl = assemble(mesh, nb, geometry, material, options);

  CircumferentialResult res;
  res.options = options;
  res.n_u = nb.n_u;
  res.n_condensed = nb.n_phi;
  // Static condensation of the potentials (eq. 92): K_c = K_UU + K_UΦ (−K_ΦΦ)⁻¹ K_ΦU,
  // −K_ΦΦ symmetric positive definite; b (V = 1) condensed alike.
  Eigen::MatrixXd kc = bl.k_uu;
  Eigen::VectorXd b = bl.b_u;
  double kvv = bl.k_vv;
  if (nb.n_phi > 0) {
    Eigen::LLT<Eigen::MatrixXd> llt(-bl.k_pp);
    if (llt.info() != Eigen::Success)
      throw std::runtime_error("circumferential_modes: the potential block is singular (harmonic " +
                               std::to_string(options.n) + "); check epsS33 > 0 and the mesh");
    const Eigen::MatrixXd x = llt.solve(bl.k_up.transpose());
    kc.noalias() += bl.k_up * x;
    const Eigen::VectorXd y = llt.solve(bl.b_p);
    b.noalias() += bl.k_up * y;
    kvv += bl.b_p.dot(y);
  }
  kc = 0.5 * (kc + kc.transpose()).eval();
  // C0 (U = 0): Q = −(K_VV V + K_VΦ Φ) with Φ condensed, V = 1. In open circuit
  // V is condensed too, so g = b and C0 come from the short-circuit numbering
  // (same displacement DOFs): p_k = gᵀφ_k of an open-circuit mode is then the
  // charge it would drive into a shorted electrode, as in model/modal.hpp.
  const bool n0cos = options.n == 0 && options.family == HarmonicFamily::cos_family;
  if (n0cos && options.electrodes == Electrodes::open_circuit) {
    CircumferentialOptions so = options;
    so.electrodes = Electrodes::short_circuit;
    const Numbering sn = number(mesh, so);
    const Blocks sb = assemble(mesh, sn, geometry, material, so);
    Eigen::LLT<Eigen::MatrixXd> llt(-sb.k_pp);
    if (llt.info() != Eigen::Success)
      throw std::runtime_error("circumferential_modes: the potential block is singular; check epsS33 > 0");
    const Eigen::VectorXd y = llt.solve(sb.b_p);
    b = sb.b_u + sb.k_up * y;
    kvv = sb.k_vv + sb.b_p.dot(y);
  }
  if (n0cos) res.c_clamped = -kvv;

  Eigen::VectorXd lam;  // ascending, φᵀMφ = 1
  Eigen::MatrixXd vec;
  if (!lanczos(kc, bl.m, options.max_frequency_hz, lam, vec)) {
    Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> ges(kc, bl.m);
    if (ges.info() != Eigen::Success)
      throw std::runtime_error("circumferential_modes: the dense eigensolver failed (harmonic " +
                               std::to_string(options.n) + "); try another mesh");
    lam = ges.eigenvalues();
    vec = ges.eigenvectors();
  }
  // Rigid motions: |ω²| far below the elastic scale (√(cE11/ρ)/L)².
  const double scale = material.c_e11 / geometry.density_kg_m3 / std::pow(geometry.length_m, 2);
  if (keep_shapes) res.shapes.resize(nb.n_u, lam.size());
  // Per-DOF component for the energy shares and the mid-plane symmetry.
  std::vector<int> comp(static_cast<std::size_t>(nb.n_u)), node_of(static_cast<std::size_t>(nb.n_u));
  for (int node = 0; node < mesh.num_nodes(); ++node)
    for (int c : {ur, ut, uz}) {
      const int i = nb.index[static_cast<std::size_t>(node * kComp + c)];
      if (i < 0) continue;
      comp[static_cast<std::size_t>(i)] = c;
      node_of[static_cast<std::size_t>(i)] = node;
    }
  for (Eigen::Index k = 0; k < lam.size(); ++k) {
    const Eigen::VectorXd phi = vec.col(k);
    CircumferentialMode md;
    md.eigenvalue = lam[k];
    md.rigid = std::abs(lam[k]) < 1e-8 * scale;
    md.omega = md.rigid ? 0.0 : std::sqrt(std::max(lam[k], 0.0));
    md.frequency_hz = md.omega / (2.0 * M_PI);
    md.kappa = phi.dot(bl.k_uu * phi);
    if (n0cos && !md.rigid) md.participation = b.dot(phi);
    const Eigen::VectorXd mphi = bl.m * phi;
    std::array<double, 3> share{0, 0, 0};
    for (int i = 0; i < nb.n_u; ++i) share[static_cast<std::size_t>(comp[static_cast<std::size_t>(i)])] += phi[i] * mphi[i];
    md.radial_share = share[ur];
    md.hoop_share = share[ut];
    md.axial_share = share[uz];
    // Mid-plane symmetry: U_r, U_θ even in z, U_z odd; energy of the even part.
    Eigen::VectorXd mir = Eigen::VectorXd::Zero(nb.n_u);
    for (int i = 0; i < nb.n_u; ++i) {
      const int node = node_of[static_cast<std::size_t>(i)];
      const int c = comp[static_cast<std::size_t>(i)];
      const int j = nb.index[static_cast<std::size_t>(mesh.mirror(node) * kComp + c)];
      mir[j] = c == uz ? -phi[i] : phi[i];
    }
    const Eigen::VectorXd sym = 0.5 * (phi + mir);
    md.symmetric = sym.dot(bl.m * sym) > 0.5;
    res.modes.push_back(md);
    if (keep_shapes) res.shapes.col(k) = phi;
  }
  return res;
}

ModalPortModel CircumferentialResult::port_model(const PiezoMaterialE& material) const {
  if (options.n != 0 || options.family != HarmonicFamily::cos_family ||
      options.electrodes != Electrodes::short_circuit)
    throw std::invalid_argument(
        "CircumferentialResult::port_model: only harmonic 0 (cos family) in short circuit carries charge");
  ModalPortModel p;
  p.c_clamped = c_clamped;
  double sum = 0;
  for (const auto& m : modes) {
    if (m.rigid) continue;
    p.modes.push_back({m.omega, m.participation, m.kappa, m.symmetric, false});
    sum += m.participation * m.participation / (m.omega * m.omega);
  }
  p.c_static = c_clamped + sum;  // all modes: exact, nothing left for a residual
  if (material.eps_s33 > 0) p.eps_t_over_s = to_d_form(material).eps_t33 / material.eps_s33;
  return p;
}

}  // namespace piezo::model
