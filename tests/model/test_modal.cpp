// Modal analysis against the seed's published numbers (shared/reference/
// published-tube-results.json, copied here): Table 3 (full APC850, 2-D model)
// and the Tables 4/5 target of the isotropic class; plus mesh convergence,
// orthonormality, symmetry and electrical participation.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "model/harmonic.hpp"
#include "model/material_presets.hpp"
#include "model/modal.hpp"

using namespace piezo::model;

namespace {

const double kTable3Short[3] = {50290.60, 53409.10, 79350.58};
const double kTable3Open[3] = {51149.01, 53992.38, 95087.15};
const double kTable45Res[3] = {51400, 55000, 82600};
const double kTable45Anti[3] = {52400, 55800, 101600};

PiezoMaterialE apc850() { return to_e_form(find_preset("apc850").material); }
PiezoMaterialE iso_target() {
  return to_e_form(to_d_form(IsotropicPiezoParams{6.66e10, 0.3333, -210e-12, 2294 * kEps0}));
}

struct Pair {
  std::vector<double> sc, oc;
};
Pair active(ModalSolver& s, const PiezoMaterialE& m, int n = 10) {
  ModalOptions o;
  o.n_modes = n;
  auto sc = s.solve(m, Electrodes::short_circuit, o);
  auto oc = s.solve(m, Electrodes::open_circuit, o);
  EXPECT_TRUE(sc.converged) << sc.message;
  EXPECT_TRUE(oc.converged) << oc.message;
  return {sc.active_frequencies_hz(), oc.active_frequencies_hz()};
}

}  // namespace

TEST(Modal, Table3FullApc850WithinPointThreePercent) {
  // Acceptance: each of the 3 + 3 frequencies within 0.3 % of the published 2-D
  // values (the seed's own 2-D and 3-D models differ by up to 0.12 %).
  TubeModel tm(TubeGeometry{}, MeshOptions{});
  ModalSolver s(tm);
  auto f = active(s, apc850());
  ASSERT_EQ(f.sc.size(), 3u);
  ASSERT_EQ(f.oc.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    const double es = f.sc[i] / kTable3Short[i] - 1, eo = f.oc[i] / kTable3Open[i] - 1;
    std::printf("Table3 short %d: %.2f Hz (published %.2f) %+.3f %%\n", i + 1, f.sc[i],
                kTable3Short[i], 100 * es);
    std::printf("Table3 open  %d: %.2f Hz (published %.2f) %+.3f %%\n", i + 1, f.oc[i],
                kTable3Open[i], 100 * eo);
    EXPECT_LT(std::abs(es), 3e-3) << "short " << i;
    EXPECT_LT(std::abs(eo), 3e-3) << "open " << i;
  }
}

TEST(Modal, Tables45IsotropicTargetWithinOnePercent) {
  TubeModel tm(TubeGeometry{}, MeshOptions{});
  ModalSolver s(tm);
  auto f = active(s, iso_target());
  ASSERT_EQ(f.sc.size(), 3u);
  ASSERT_EQ(f.oc.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    const double es = f.sc[i] / kTable45Res[i] - 1, eo = f.oc[i] / kTable45Anti[i] - 1;
    std::printf("Table4/5 resonance %d: %.1f Hz (%.0f) %+.3f %%; anti-resonance %.1f Hz (%.0f) %+.3f %%\n",
                i + 1, f.sc[i], kTable45Res[i], 100 * es, f.oc[i], kTable45Anti[i], 100 * eo);
    EXPECT_LT(std::abs(es), 1e-2);
    EXPECT_LT(std::abs(eo), 1e-2);
  }
}

TEST(Modal, MeshConvergence) {
  // Q2 elements: frequency error ~ h⁴; successive differences must shrink and the
  // default mesh must sit within 1e-5 of the finest one (discretisation error is
  // two orders below the 0.3 % acceptance band).
  const MeshOptions meshes[] = {{1, 6}, {1, 12}, {2, 24}, {4, 48}, {8, 96}};
  std::vector<Pair> res;
  std::printf("mesh (n_r x n_z)   n_u   short-circuit [Hz]            open-circuit [Hz]\n");
  for (const auto& m : meshes) {
    TubeModel tm(TubeGeometry{}, m);
    ModalSolver s(tm);
    res.push_back(active(s, apc850()));
    ASSERT_EQ(res.back().sc.size(), 3u);
    ASSERT_EQ(res.back().oc.size(), 3u);
    const auto& r = res.back();
    std::printf("%2d x %-3d        %5d   %.2f %.2f %.2f   %.2f %.2f %.2f\n", m.n_radial, m.n_axial,
                tm.n_u(), r.sc[0], r.sc[1], r.sc[2], r.oc[0], r.oc[1], r.oc[2]);
  }
  const Pair& fine = res.back();
  auto maxdiff = [&](const Pair& a, const Pair& b) {
    double d = 0;
    for (int i = 0; i < 3; ++i)
      d = std::max({d, std::abs(a.sc[i] / b.sc[i] - 1), std::abs(a.oc[i] / b.oc[i] - 1)});
    return d;
  };
  for (std::size_t k = 1; k + 1 < res.size(); ++k)
    EXPECT_LT(maxdiff(res[k], fine), maxdiff(res[k - 1], fine)) << "mesh " << k;
  EXPECT_LT(maxdiff(res[2], fine), 1e-5);  // default mesh {2, 24}
}

TEST(Modal, ShapesRigidModeSymmetryAndParticipation) {
  TubeModel tm(TubeGeometry{}, MeshOptions{});
  ModalSolver s(tm);
  ModalOptions o;
  o.n_modes = 10;
  auto sc = s.solve(apc850(), Electrodes::short_circuit, o);
  ASSERT_TRUE(sc.converged);
  ASSERT_EQ(sc.modes.size(), 10u);
  // Mass-normalised and M-orthogonal (Lanczos tolerance 1e-10).
  const Eigen::MatrixXd g = sc.shapes.transpose() * (tm.split().m * sc.shapes);
  EXPECT_LT((g - Eigen::MatrixXd::Identity(10, 10)).cwiseAbs().maxCoeff(), 1e-8);
  // Mode 0: the free-free rigid axial translation, antisymmetric and inactive.
  EXPECT_LT(sc.modes[0].frequency_hz, 1.0);
  EXPECT_EQ(sc.modes[0].symmetry, Symmetry::antisymmetric);
  EXPECT_FALSE(sc.modes[0].electrically_active);
  for (std::size_t k = 1; k < sc.modes.size(); ++k) {
    const auto& m = sc.modes[k];
    EXPECT_GE(m.frequency_hz, sc.modes[k - 1].frequency_hz);
    // Each mode is cleanly symmetric or antisymmetric (no near-degeneracies here).
    EXPECT_NE(m.symmetry, Symmetry::mixed) << k;
    // Antisymmetric modes cannot be driven by the uniform electrode: p = 0 to round-off.
    if (m.symmetry == Symmetry::antisymmetric) {
      EXPECT_LT(m.coupling, 1e-15) << k;
    }
    if (m.electrically_active) {
      EXPECT_GT(m.coupling, 1e-2) << k;
    }
  }
  // Open circuit stiffens: each active anti-resonance above its resonance (interlacing).
  auto oc = s.solve(apc850(), Electrodes::open_circuit, o);
  auto fs = sc.active_frequencies_hz(), fo = oc.active_frequencies_hz();
  ASSERT_EQ(fs.size(), fo.size());
  for (std::size_t i = 0; i < fs.size(); ++i) {
    EXPECT_GT(fo[i], fs[i]);
    if (i + 1 < fs.size()) {
      EXPECT_LT(fo[i], fs[i + 1]);
    }
  }
}

TEST(Modal, CapacitancesAgainstAnalytic) {
  // Low-frequency (unclamped) capacitance of the free tube vs eq. 200 with εT33,
  // within 0.5 % (acceptance); the clamped one must be much lower.
  TubeModel tm(TubeGeometry{}, MeshOptions{});
  ModalSolver s(tm);
  const auto m = iso_target();
  const double cs = s.static_capacitance(m);
  const double ca = tm.analytic_capacitance(2294 * kEps0);
  std::printf("C_static = %.6e F, analytic 2π εT33 L/ln(Do/Di) = %.6e F (%+.3f %%)\n", cs, ca,
              100 * (cs / ca - 1));
  EXPECT_LT(std::abs(cs / ca - 1), 5e-3);
  const double c0 = s.clamped_capacitance(m);
  EXPECT_LT(c0, 0.5 * cs);
  EXPECT_GT(c0, tm.analytic_capacitance(iso_target().eps_s33) * 0.99);
  // |Z(400 Hz)| of Tables 4/5 (26804 Ω) within 0.5 %; at 400 Hz the dynamic part
  // is (400/51400)² ≈ 6e-5 of the static one.
  const double z400 = 1.0 / (2 * M_PI * 400 * cs);
  std::printf("|Z(400 Hz)| ≈ 1/(ωC_static) = %.1f Ω (published 26804) %+.3f %%\n", z400,
              100 * (z400 / 26804 - 1));
  EXPECT_LT(std::abs(z400 / 26804 - 1), 5e-3);
}

TEST(Modal, ReweightingWithoutReassemblyAndStatus) {
  // One solver, many materials: results equal a fresh model's (symbolic reuse is sound).
  TubeModel tm(TubeGeometry{}, {2, 12});
  ModalSolver s(tm);
  auto a = active(s, apc850());
  auto b = active(s, iso_target());
  auto c = active(s, apc850());
  for (int i = 0; i < 3; ++i) {
    EXPECT_DOUBLE_EQ(a.sc[i], c.sc[i]);
    EXPECT_NE(a.sc[i], b.sc[i]);
  }
  ModalOptions bad;
  bad.n_modes = 0;
  EXPECT_THROW(s.solve(apc850(), Electrodes::short_circuit, bad), std::invalid_argument);
  // Non-convergence is a status: one iteration cannot converge 10 modes.
  ModalOptions tight;
  tight.max_iterations = 1;
  tight.ncv = 11;
  auto r = s.solve(apc850(), Electrodes::short_circuit, tight);
  EXPECT_FALSE(r.converged);
  EXPECT_FALSE(r.message.empty());
}

// The port model on the upper half with u_z = 0 on the mid-plane (ModalOptions::
// mirror_symmetry, the default) against the whole tube's: the same symmetric
// modes (frequency, participation and κ to the Lanczos tolerance) and the same
// C0 and C_static, bare and with an end-face mass (half of it on each face: the
// half model carries its top face's share). Tolerances: 1e-7 relative on the
// modal data (Lanczos tolerance 1e-10 on the shift-inverted eigenvalues, square
// root and normalisation on top). The two differ only in the truncation: the
// half keeps more symmetric modes for the same cost, and its residual mode
// stands for fewer, so against the exact direct solve (model/harmonic.hpp) it
// is at least as close as the whole tube's port everywhere up to 300 kHz
// (measured: 6.0e-4 both below 120 kHz — the modal Rayleigh approximation —,
// 1.1e-3 vs 1.2e-2 from 120 to 300 kHz).
TEST(Modal, MirrorSymmetryPortEqualsTheWholeTube) {
  TubeModel tm(TubeGeometry{}, MeshOptions{});
  ModalSolver s(tm);
  for (const double f_end : {0.0, 0.03}) {
    ModalOptions whole;
    whole.n_modes = 16;
    whole.end_mass_fraction = f_end;
    whole.mirror_symmetry = false;
    ModalOptions half = whole;
    half.mirror_symmetry = true;
    const auto pw = s.port_model(iso_target(), whole);
    const auto ph = s.port_model(iso_target(), half);
    ASSERT_TRUE(pw.converged && ph.converged);
    EXPECT_NEAR(ph.c_clamped / pw.c_clamped, 1.0, 1e-9) << "f_end " << f_end;
    EXPECT_NEAR(ph.c_static / pw.c_static, 1.0, 1e-9) << "f_end " << f_end;
    // Every symmetric mode of the whole tube is a mode of the half.
    int matched = 0;
    for (const auto& m : pw.modes) {
      if (!m.symmetric || m.residual) continue;
      const PortMode* best = nullptr;
      for (const auto& h : ph.modes)
        if (!h.residual && (!best || std::abs(h.omega - m.omega) < std::abs(best->omega - m.omega)))
          best = &h;
      ASSERT_NE(best, nullptr);
      EXPECT_NEAR(best->omega / m.omega, 1.0, 1e-7) << m.omega / (2 * M_PI) << " Hz, f_end " << f_end;
      EXPECT_NEAR(std::abs(best->participation) / std::abs(m.participation), 1.0, 1e-6)
          << m.omega / (2 * M_PI) << " Hz, f_end " << f_end;
      EXPECT_NEAR(best->kappa / m.kappa, 1.0, 1e-6) << m.omega / (2 * M_PI) << " Hz";
      ++matched;
    }
    EXPECT_GE(matched, 7) << "f_end " << f_end;
    if (f_end > 0) continue;
    RayleighDamping d;
    d.beta = 1e-7;
    std::vector<double> f;
    for (double x = 2000; x <= 300000; x += 2000) f.push_back(x);
    const auto yd = DirectHarmonicSolver(tm).admittance(iso_target(), f, d);
    const auto yw = admittance_modal(pw, f, d);
    const auto yh = admittance_modal(ph, f, d);
    double ew[2] = {0, 0}, eh[2] = {0, 0};
    for (std::size_t i = 0; i < f.size(); ++i) {
      const int band = f[i] <= 120000 ? 0 : 1;
      ew[band] = std::max(ew[band], std::abs(yw[i] - yd[i]) / std::abs(yd[i]));
      eh[band] = std::max(eh[band], std::abs(yh[i] - yd[i]) / std::abs(yd[i]));
    }
    std::printf("vs direct, worst relative |dY|: <= 120 kHz whole %.2e half %.2e; 120-300 kHz whole %.2e half %.2e\n",
                ew[0], eh[0], ew[1], eh[1]);
    EXPECT_LE(eh[0], ew[0] * 1.01);
    EXPECT_LE(eh[1], ew[1] * 1.01);
  }
}
