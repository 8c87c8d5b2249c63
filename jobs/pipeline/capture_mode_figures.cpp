#include "jobs/pipeline/capture_mode_figures.hpp"

#include <stdexcept>

namespace piezo::jobs {

CaptureModeFigures capture_mode_figures(const acq::Capture& cap, const dsp::ImpedanceResult& z) {
  CaptureModeFigures out;
  const auto g = cap.setup.geometry();
  const bool given = cap.setup.inner_diameter_m && cap.setup.outer_diameter_m;
  dsp::ModeFigureOptions o;
  o.mean_diameter_m = 0.5 * (g.inner_diameter_m + g.outer_diameter_m);
  out.mean_diameter_m = o.mean_diameter_m;
  out.mean_diameter_source =
      given ? "capture /setup" : "the project's default tube (not in the capture)";
  const Eigen::VectorXd sigma =
      z.z_sigma_ohm.size() == z.f_hz.size() ? z.z_sigma_ohm : Eigen::VectorXd();
  try {
    out.figures = dsp::mode_figures(z.f_hz, z.z_ohm, sigma, o);
  } catch (const std::invalid_argument& e) {  // a grid too short for figures: the impedance stands
    out.error = e.what();
  }
  return out;
}

}  // namespace piezo::jobs
