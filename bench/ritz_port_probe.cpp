// A measurement for issue 43's next step (docs/benchmarks.md, "Where the port
// models go"): how well a Ritz port model — the short-circuit mode shapes and
// the static shapes of a point x0 and of its four plus-points x0 + h·e_i as a
// basis, the short-circuit stiffness at x projected on it — reproduces the
// exact port model (ModalSolver: Lanczos on the factorised system) at points
// x near x0, and what a Ritz solve costs. Four coordinates as the fit's
// (relative changes of cE11, cE12, e31 and εS33). Not a product path: it
// prints numbers, it asserts nothing. Run: build/bench/ritz_port_probe.
#include <Eigen/Dense>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "model/material_spec.hpp"
#include "model/modal.hpp"
#include "model/tube_model.hpp"

namespace {
using namespace piezo;
using Mat = Eigen::MatrixXd;
using Vec = Eigen::VectorXd;

model::PiezoMaterialE at(const model::PiezoMaterialE& m0, const Vec& x) {
  model::PiezoMaterialE m = m0;
  m.c_e11 *= 1 + x[0];
  m.c_e12 *= 1 + x[1];
  m.e31 *= 1 + x[2];
  m.eps_s33 *= 1 + x[3];
  return m;
}

// Short-circuit stiffness K_UU − K_UΦi K_ΦΦii⁻¹ K_ΦiU (the electrode's potential
// 0, the interior potentials condensed; K_ΦΦ is negative: the coupling stiffens).
Mat short_circuit_stiffness(const model::TubeModel& tm, const model::PiezoMaterialE& m) {
  const auto a = tm.assemble(m);
  const int ni = tm.n_phi() - 1;  // the last potential is the electrode
  const Mat kuu = Mat(a.k_uu), kup = Mat(a.k_uphi).leftCols(ni), kpp = Mat(a.k_phiphi).topLeftCorner(ni, ni);
  return kuu - kup * kpp.ldlt().solve(kup.transpose());
}

struct Pair {
  double omega, p;
};

}  // namespace

int main() {
  const auto mat = model::resolve_material({"apc850", false, ""});
  model::TubeGeometry g;
  g.density_kg_m3 = mat.density_kg_m3;
  const model::TubeModel tm(g);
  model::ModalSolver solver(tm);
  const auto m0 = model::to_e_form(mat.d);
  model::ModalOptions mo;
  mo.n_modes = 24;
  const Mat mass = Mat(tm.mass(0.0));
  const Vec x0 = Vec::Zero(4);

  for (double h : {1e-3, 1e-6}) {
    // The basis: modes and static shapes at x0 and its plus-points.
    std::vector<Vec> cols;
    for (int c = -1; c < 4; ++c) {
      Vec x = x0;
      if (c >= 0) x[c] += h;
      const auto r = solver.solve(at(m0, x), model::Electrodes::short_circuit, mo);
      for (Eigen::Index k = 0; k < r.shapes.cols(); ++k) cols.push_back(r.shapes.col(k));
      Vec us;
      solver.static_capacitance(at(m0, x), &us);
      cols.push_back(us);
    }
    Mat v(mass.rows(), static_cast<Eigen::Index>(cols.size()));
    for (std::size_t k = 0; k < cols.size(); ++k)  // each column at unit M-norm (the static shapes are ~1e-10 m)
      v.col(static_cast<Eigen::Index>(k)) = cols[k] / std::sqrt(cols[k].dot(mass * cols[k]));
    // M-orthonormal basis of their span (directions below 1e-12 of the largest dropped).
    Eigen::SelfAdjointEigenSolver<Mat> gram(v.transpose() * mass * v);
    const double gmax = gram.eigenvalues().maxCoeff();
    int keep = 0;
    for (Eigen::Index k = 0; k < gram.eigenvalues().size(); ++k) keep += gram.eigenvalues()[k] > 1e-24 * gmax;
    const Mat w = gram.eigenvectors().rightCols(keep) *
                  gram.eigenvalues().tail(keep).cwiseSqrt().cwiseInverse().asDiagonal();
    const Mat basis = v * w;
    std::printf("h %.0e: basis of %d vectors (of %zu)\n", h, keep, cols.size());

    std::mt19937_64 rng(7);
    std::normal_distribution<double> nd;
    for (double reach : {1e-4, 1e-3, 1e-2, 3e-2}) {
      double worst_w = 0, worst_p = 0;
      double t_ritz = 0, worst_lanczos_p = 0;
      for (int trial = 0; trial < 4; ++trial) {
        Vec x(4);
        for (int i = 0; i < 4; ++i) x[i] = nd(rng);
        x *= reach / x.cwiseAbs().maxCoeff();
        const auto mx = at(m0, x);
        const auto exact = solver.solve(mx, model::Electrodes::short_circuit, mo);
        model::ModalOptions tight = mo;
        tight.tolerance = 1e-15;
        const auto exact2 = solver.solve(mx, model::Electrodes::short_circuit, tight);
        for (std::size_t k = 0; k < exact.modes.size(); ++k)
          if (exact.modes[k].electrically_active)
            worst_lanczos_p = std::max(worst_lanczos_p, std::abs(std::abs(exact2.modes[k].participation) -
                                                                  std::abs(exact.modes[k].participation)) /
                                                           std::abs(exact2.modes[k].participation));
        Vec gvec;
        solver.clamped_capacitance(mx, &gvec);
        const Mat ksc = short_circuit_stiffness(tm, mx);
        const auto t0 = std::chrono::steady_clock::now();
        const Mat kr = basis.transpose() * ksc * basis;
        Eigen::SelfAdjointEigenSolver<Mat> es(0.5 * (kr + kr.transpose()));
        t_ritz += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        // Each exact active mode against the Ritz pair nearest in ω.
        for (std::size_t k = 0; k < exact.modes.size(); ++k) {
          const auto& em = exact.modes[k];
          if (!em.electrically_active) continue;
          Eigen::Index best = 0;
          double dist = 1e300;
          for (Eigen::Index j = 0; j < es.eigenvalues().size(); ++j) {
            const double d = std::abs(std::sqrt(std::max(0.0, es.eigenvalues()[j])) - em.omega);
            if (d < dist) dist = d, best = j;
          }
          const double pr = std::abs(gvec.dot(basis * es.eigenvectors().col(best)));
          worst_w = std::max(worst_w, dist / em.omega);
          worst_p = std::max(worst_p, std::abs(pr - std::abs(em.participation)) / std::abs(em.participation));
        }
      }
      std::printf("  (Lanczos at tolerance 1e-10 against 1e-15: |Δp|/p %.2e)\n", worst_lanczos_p);
      std::printf("  reach %.0e: worst active-mode |Δω|/ω %.2e, |Δp|/p %.2e; projection + %ld-dim eigen %.3f ms "
                  "(dense, not the affine form)\n",
                  reach, worst_w, worst_p, static_cast<long>(basis.cols()), 1e3 * t_ritz / 4);
    }
  }
  return 0;
}
