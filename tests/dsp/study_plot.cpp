#include "study_plot.hpp"

#include <cmath>
#include <complex>
#include <numbers>

namespace piezo::study {

namespace {

// Fixed colours for the study's methods (the same in every panel and figure).
std::string colour_of(const StudyRow& r, std::size_t k) {
  if (r.method == "prony") return r.samples <= 1000 ? "#ff7f0e" : "#1f77b4";
  if (r.method.rfind("fft", 0) == 0) return "#2ca02c";
  if (r.method.rfind("xspec", 0) == 0) return "#d62728";
  static constexpr const char* kOthers[] = {"#9467bd", "#8c564b", "#e377c2", "#17becf"};
  return kOthers[k % (sizeof kOthers / sizeof kOthers[0])];
}

// The noisy FFT-based curves thinner, so the smooth ones drawn over them stay visible.
double width_of(const StudyRow& r) { return r.method == "prony" ? 1.6 : 0.8; }

std::string label_of(const StudyRow& r) {
  return r.method + " (" + std::to_string(r.samples) + ")";
}

double phase_deg(std::complex<double> z) { return std::arg(z) * 180.0 / std::numbers::pi; }

jobs::report::Panel panel(const char* title, const char* y_label, jobs::report::Scale x, jobs::report::Scale y) {
  jobs::report::Panel p;
  p.title = title;
  p.x_label = "frequency (Hz)";
  p.y_label = y_label;
  p.x_scale = x;
  p.y_scale = y;
  return p;
}

jobs::report::Series series(const std::string& label, const std::string& colour, double width,
                      bool dashed = false) {
  jobs::report::Series s;
  s.label = label;
  s.colour = colour;
  s.width = width;
  s.dashed = dashed;
  return s;
}

}  // namespace

jobs::report::Figure comparison_figure(const StudyInput& in, const std::vector<StudyRow>& rows,
                                 const std::vector<ErrorBand>& bands, const std::string& title) {
  jobs::report::Figure fig;
  fig.title = title;
  fig.width = 1000;
  fig.panel_height = 340;

  // The truth on a fine grid (the features are sharp at β = 1e-7).
  std::vector<double> ft;
  for (double f = in.f_lo_hz; f <= in.f_hi_hz * (1 + 1e-12); f *= 1.002) ft.push_back(f);
  jobs::report::Series mag_true = series("true (FE modal)", "#000000", 2.5);
  mag_true.x = ft;
  jobs::report::Series ph_true = mag_true;
  for (double f : ft) {
    const auto z = in.z_true(f);
    mag_true.y.push_back(std::abs(z));
    ph_true.y.push_back(phase_deg(z));
  }

  using jobs::report::Scale;
  jobs::report::Panel mag = panel("|Z|", "|Z| (ohm)", Scale::Log, Scale::Log);
  jobs::report::Panel zoom = panel("|Z|, 45-100 kHz", "|Z| (ohm)", Scale::Linear, Scale::Log);
  jobs::report::Panel ph = panel("phase", "phase (deg)", Scale::Log, Scale::Linear);
  jobs::report::Panel err =
      panel("|Z| error: 20 log10(|Z est| / |Z true|)", "error (dB)", Scale::Log, Scale::Linear);
  jobs::report::Panel err_zoom =
      panel("|Z| error, 45-100 kHz", "error (dB)", Scale::Linear, Scale::Linear);
  mag.x_range = ph.x_range = err.x_range = std::make_pair(in.f_lo_hz, in.f_hi_hz);
  zoom.x_range = err_zoom.x_range = std::make_pair(45e3, 100e3);
  err_zoom.y_range = std::make_pair(-4.0, 4.0);
  ph.y_range = std::make_pair(-100.0, 100.0);
  err.y_range = std::make_pair(-6.0, 6.0);

  for (std::size_t k = 0; k < rows.size(); ++k) {
    const auto& r = rows[k];
    jobs::report::Series m = series(label_of(r), colour_of(r, k), width_of(r));
    jobs::report::Series p = m, e = m;
    for (std::size_t i = 0; i < r.f_hz.size(); ++i) {
      const double f = r.f_hz[i];
      if (f < in.f_lo_hz || f > in.f_hi_hz) continue;
      const auto z = r.z_ohm[i];
      m.x.push_back(f);
      m.y.push_back(std::abs(z));
      p.x.push_back(f);
      p.y.push_back(phase_deg(z));
      e.x.push_back(f);
      e.y.push_back(20.0 * std::log10(std::abs(z) / std::abs(in.z_true(f))));
    }
    mag.series.push_back(m);
    zoom.series.push_back(m);
    ph.series.push_back(p);
    err.series.push_back(e);
    err_zoom.series.push_back(e);
  }
  // The truth last, drawn over the estimates.
  mag.series.push_back(mag_true);
  zoom.series.push_back(mag_true);
  ph.series.push_back(ph_true);

  for (const auto& b : bands) {
    jobs::report::Series up = series(b.label, b.colour, 1.5, true), dn = series("", b.colour, 1.5, true);
    up.x = dn.x = b.f_hz;
    for (double s : b.sigma_db) {
      up.y.push_back(s);
      dn.y.push_back(-s);
    }
    for (auto* p : {&err, &err_zoom}) {
      p->series.push_back(up);
      p->series.push_back(dn);
    }
  }
  for (auto* p : {&err, &err_zoom}) {
    p->hlines.push_back(jobs::report::HLine{1.0, "#444444", true, "+1 dB target"});
    p->hlines.push_back(jobs::report::HLine{-1.0, "#444444", true, "-1 dB"});
  }
  for (const auto* v : {&in.true_resonances_hz, &in.true_antiresonances_hz})
    for (double f : *v)
      for (auto* p : {&mag, &zoom, &ph, &err, &err_zoom})
        p->markers.push_back(jobs::report::VMarker{f, "#bbbbbb"});

  // The zoom panels keep only their points in range (+1 on each side): the
  // writer clips, but the file would carry every point.
  for (auto* p : {&zoom, &err_zoom})
    for (auto& ser : p->series) {
      jobs::report::Series kept = ser;
      kept.x.clear();
      kept.y.clear();
      for (std::size_t i = 0; i < ser.x.size(); ++i) {
        const bool in_range = ser.x[i] >= p->x_range->first && ser.x[i] <= p->x_range->second;
        const bool next_in = i + 1 < ser.x.size() && ser.x[i + 1] >= p->x_range->first;
        const bool prev_in = i > 0 && ser.x[i - 1] <= p->x_range->second;
        if (in_range || (next_in && ser.x[i] < p->x_range->first) ||
            (prev_in && ser.x[i] > p->x_range->second)) {
          kept.x.push_back(ser.x[i]);
          kept.y.push_back(ser.y[i]);
        }
      }
      ser = kept;
    }
  fig.panels = {mag, zoom, ph, err, err_zoom};
  return fig;
}

void write_comparison_svg(const jobs::report::Figure& fig, const std::filesystem::path& file) {
  if (file.has_parent_path()) std::filesystem::create_directories(file.parent_path());
  jobs::report::write_svg(fig, file);
}

}  // namespace piezo::study
