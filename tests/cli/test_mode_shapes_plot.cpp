// jobs/report/mode_shapes_plot: the deformed section of each mode (seed Figs
// 7, 12, 13) against what a mode's symmetry about the mid-plane z = 0 demands
// of its nodes (modal.hpp's classification, an independent computation from
// the shapes' M-weighted symmetric fraction): a symmetric mode has u_r even
// and u_z odd in z, an antisymmetric one u_r odd and u_z even; and the scale
// (the largest displacement drawn as half the wall).
#include <gtest/gtest.h>

#include <cmath>

#include "jobs/report/mode_shapes_plot.hpp"
#include "model/material_spec.hpp"
#include "model/modal.hpp"
#include "model/tube_model.hpp"

namespace {
using namespace piezo;

TEST(ModeShapesPlot, DeformedSectionHasTheModesSymmetryAndScale) {
  const auto mat = model::resolve_material({"apc850", false, ""});
  model::TubeGeometry g;
  g.density_kg_m3 = mat.density_kg_m3;
  const model::TubeModel tube(g);
  model::ModalSolver solver(tube);
  model::ModalOptions o;
  o.n_modes = 10;
  const auto e = model::to_e_form(mat.d);
  const auto sc = solver.solve(e, model::Electrodes::short_circuit, o);
  const auto oc = solver.solve(e, model::Electrodes::open_circuit, o);
  const auto fig = jobs::report::mode_shapes_figure(tube.mesh(), sc, oc, "test");
  ASSERT_EQ(fig.panels.size(), 9u);  // three active per circuit, three antisymmetric
  const int nr = tube.mesh().nodes_r(), nz = tube.mesh().nodes_z();
  const double wall = 1e3 * (g.outer_diameter_m - g.inner_diameter_m) / 2;
  for (std::size_t p = 0; p < fig.panels.size(); ++p) {
    const bool symmetric = p < 6;
    const auto& s = fig.panels[p].series;
    // Series: nr lines along z and the element edges, at rest, then the same deformed.
    const std::size_t per_state = s.size() / 2;
    double worst = 0, largest = 0;
    for (int ir = 0; ir < nr; ++ir) {
      const auto& rest = s[static_cast<std::size_t>(ir)];
      const auto& def = s[per_state + static_cast<std::size_t>(ir)];
      ASSERT_EQ(def.x.size(), static_cast<std::size_t>(nz));
      for (int k = 0; k < nz; ++k) {
        const auto m = static_cast<std::size_t>(nz - 1 - k), i = static_cast<std::size_t>(k);
        const double ur = def.y[i] - rest.y[i], urm = def.y[m] - rest.y[m];
        const double uz = def.x[i] - rest.x[i], uzm = def.x[m] - rest.x[m];
        largest = std::max(largest, std::hypot(ur, uz));
        worst = std::max(worst, symmetric ? std::abs(ur - urm) + std::abs(uz + uzm)
                                          : std::abs(ur + urm) + std::abs(uz - uzm));
      }
    }
    EXPECT_LT(worst, 1e-6 * wall) << fig.panels[p].title;
    EXPECT_NEAR(largest, 0.5 * wall, 1e-9 * wall) << fig.panels[p].title;
  }
}

}  // namespace
