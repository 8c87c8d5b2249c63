// The jobs' room (jobs/report): the mode-shape figure (see mode_shapes_plot.hpp).
#include "jobs/report/mode_shapes_plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>

namespace piezo::jobs::report {

namespace {

namespace pm = piezo::model;

// One panel: the section in mm, z along x (the length), r along y (the wall).
Panel shape_panel(const pm::TubeMesh& mesh, const Eigen::VectorXd& phi, const std::string& title,
                  double wall_share) {
  const auto& nodes = mesh.nodes();
  const int nr = mesh.nodes_r(), nz = mesh.nodes_z();
  double rmin = 1e300, rmax = -1e300, zmin = 1e300, zmax = -1e300, umax = 0;
  for (int n = 0; n < mesh.num_nodes(); ++n) {
    rmin = std::min(rmin, nodes[n].r);
    rmax = std::max(rmax, nodes[n].r);
    zmin = std::min(zmin, nodes[n].z);
    zmax = std::max(zmax, nodes[n].z);
    umax = std::max(umax, std::hypot(phi[2 * n], phi[2 * n + 1]));
  }
  const double wall = rmax - rmin;
  const double s = umax > 0 ? wall_share * wall / umax : 0.0;
  Panel p;
  p.title = title;
  p.x_label = "z [mm]";
  p.y_label = "r [mm]";
  p.height_weight = 1;
  auto line = [&](bool deformed, bool along_z, int fixed, bool listed) {
    Series ser{listed ? (deformed ? "deformed" : "at rest") : ""};
    ser.listed = listed;
    ser.colour = deformed ? "#1f77b4" : "#bbbbbb";
    ser.width = deformed ? 1.4 : 1.0;
    const int count = along_z ? nz : nr;
    for (int k = 0; k < count; ++k) {
      const int n = along_z ? mesh.node_index(fixed, k) : mesh.node_index(k, fixed);
      const double dr = deformed ? s * phi[2 * n] : 0.0, dz = deformed ? s * phi[2 * n + 1] : 0.0;
      ser.x.push_back(1e3 * (nodes[n].z + dz));
      ser.y.push_back(1e3 * (nodes[n].r + dr));
    }
    return ser;
  };
  for (bool deformed : {false, true}) {
    bool first = true;
    for (int ir = 0; ir < nr; ++ir) p.series.push_back(line(deformed, true, ir, std::exchange(first, false)));
    for (int iz = 0; iz < nz; iz += 2) p.series.push_back(line(deformed, false, iz, false));  // element edges
  }
  const double pad = (wall_share + 0.15) * wall;
  p.y_range = std::make_pair(1e3 * (rmin - pad), 1e3 * (rmax + pad));
  const double zpad = (wall_share + 0.15) * wall;
  p.x_range = std::make_pair(1e3 * (zmin - zpad), 1e3 * (zmax + zpad));
  return p;
}

std::string title_of(const pm::Mode& m, pm::Electrodes e) {
  char buf[200];
  std::snprintf(buf, sizeof buf, "%s circuit, %s: %.1f Hz", e == pm::Electrodes::short_circuit ? "short" : "open",
                pm::to_string(m.symmetry), m.frequency_hz);
  std::string t = buf;
  if (m.electrically_active) {
    std::snprintf(buf, sizeof buf, ", active, coupling %.3g", m.coupling);
    t += buf;
  }
  return t;
}

}  // namespace

Figure mode_shapes_figure(const pm::TubeMesh& mesh, const pm::ModalResult& sc, const pm::ModalResult& oc,
                          const std::string& subtitle, const ModeShapesOptions& opt) {
  Figure fig;
  fig.title = "Seed Figs 7, 12, 13: the tube's modes (r-z section, displacement exaggerated)";
  fig.subtitle = subtitle;
  fig.note = "each panel scaled so that its largest displacement is " +
             std::to_string(static_cast<int>(std::lround(100 * opt.wall_share))) +
             " % of the wall; grey: at rest; the axis of revolution is below (r = 0)";
  fig.panel_height = 150;
  auto add = [&](const pm::ModalResult& res, bool symmetric, int count) {
    int n = 0;
    for (std::size_t k = 0; k < res.modes.size() && n < count; ++k) {
      const auto& m = res.modes[k];
      if (!(m.omega > 0)) continue;  // the rigid-body mode
      const bool take = symmetric ? m.electrically_active : m.symmetry == pm::Symmetry::antisymmetric;
      if (!take) continue;
      fig.panels.push_back(shape_panel(mesh, res.shapes.col(static_cast<Eigen::Index>(k)),
                                       title_of(m, res.electrodes), opt.wall_share));
      ++n;
    }
  };
  add(sc, true, opt.symmetric);
  add(oc, true, opt.symmetric);
  add(sc, false, opt.antisymmetric);
  // The legend once, on the first panel.
  for (std::size_t k = 1; k < fig.panels.size(); ++k)
    for (auto& ser : fig.panels[k].series) ser.listed = false;
  return fig;
}

}  // namespace piezo::jobs::report
