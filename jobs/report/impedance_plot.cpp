#include "jobs/report/impedance_plot.hpp"

#include <cmath>
#include <numbers>

namespace piezo::jobs::report {

namespace {

struct Style {
  const char* colour;
  double width;
  bool dashed;
};

Style style_for(const std::string& label) {
  if (label.find("updated") != std::string::npos) return {"#2ca02c", 4.0, false};
  if (label.find("original") != std::string::npos) return {"#ff7f0e", 1.8, true};
  return {"#1f1f7a", 1.4, false};  // the Prony-SS estimate the update used
}

}  // namespace

Figure impedance_figure(const jobs::PipelineResult& r, const std::string& title) {
  Panel mag{"|Z|", "frequency [Hz]", "|Z| [ohm]", Scale::Log, Scale::Log, {}, {}, {}, {}, {}};
  Panel ph{"phase",
           "frequency [Hz]",
           "phase [deg]",
           Scale::Log,
           Scale::Linear,
           {},
           std::pair(-95.0, 95.0),
           {},
           {},
           {}};
  // Models first (the updated one wide, as a halo), the measurement on top.
  // The FFT and cross-spectra overlays stay out, as in the GUI's default view
  // (they are noisy on a few shots; the results file keeps them).
  auto overlay = [](const std::string& l) {
    return l.find("FFT") != std::string::npos || l.find("cross") != std::string::npos;
  };
  std::vector<const jobs::Curve*> order;
  for (const auto& c : r.curves)
    if (c.label.find("model") != std::string::npos) order.push_back(&c);
  for (const auto& c : r.curves)
    if (c.label.find("model") == std::string::npos && !overlay(c.label)) order.push_back(&c);
  for (const jobs::Curve* c : order) {
    const Style st = style_for(c->label);
    Series m{c->label, c->f_hz, {}, st.colour, st.width, st.dashed, false};
    Series p{"", c->f_hz, {}, st.colour, st.width, st.dashed, false};
    for (const auto& z : c->z_ohm) {
      m.y.push_back(std::abs(z));
      p.y.push_back(std::arg(z) * 180.0 / std::numbers::pi);
    }
    mag.series.push_back(std::move(m));
    ph.series.push_back(std::move(p));
  }
  for (double f : r.resonances_hz) {
    mag.markers.push_back({f, "#d62728"});
    ph.markers.push_back({f, "#d62728"});
  }
  for (double f : r.antiresonances_hz) {
    mag.markers.push_back({f, "#9467bd"});
    ph.markers.push_back({f, "#9467bd"});
  }
  if (!r.resonances_hz.empty() || !r.antiresonances_hz.empty()) {
    // Legend entries for the markers (no data: nothing drawn in the plot).
    mag.series.push_back({"resonance (Prony zero)", {}, {}, "#d62728", 1.0, true, false});
    mag.series.push_back({"anti-resonance (Prony pole)", {}, {}, "#9467bd", 1.0, true, false});
  }
  Figure fig;
  fig.title = title;
  fig.width = 960;
  fig.panel_height = 340;
  fig.panels = {std::move(mag), std::move(ph)};
  return fig;
}

}  // namespace piezo::jobs::report
