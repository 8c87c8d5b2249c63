#include "dsp/stabilization.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace piezo::dsp {

const char* to_string(PoleStability s) {
  switch (s) {
    case PoleStability::New:
      return "new";
    case PoleStability::StableFrequency:
      return "stable_freq";
    case PoleStability::Stable:
      return "stable";
  }
  return "new";
}

StabilizationChart stabilization_chart(const DividerRecord& rec, const PronyImpedanceOptions& opt,
                                       const StabilizationOptions& s) {
  if (s.min_order < 1 || s.max_order < s.min_order || s.step < 1)
    throw std::invalid_argument(
        "stabilization_chart: need 1 <= min_order <= max_order and step >= 1");
  if (!(s.freq_tol > 0) || !(s.damping_tol > 0))
    throw std::invalid_argument("stabilization_chart: tolerances must be positive");
  StabilizationChart chart;
  // Every row and the automatic order from one decomposition (the chart's
  // orders are truncations of the same SVD).
  std::vector<std::size_t> orders{0};
  for (std::size_t p = s.min_order; p <= s.max_order; p += s.step) orders.push_back(p);
  std::vector<std::optional<PronyImpedance>> fits;
  try {
    fits = fit_prony_impedance_orders(rec, opt, orders);
  } catch (const std::invalid_argument&) {
    return chart;  // the record carries no fit at any order: an empty chart
  }
  chart.selected_order = fits[0] ? fits[0]->fit.order : 0;
  std::vector<PoleInfo> previous;
  bool have_previous = false;
  for (std::size_t row = 1; row < orders.size(); ++row) {
    const std::size_t p = orders[row];
    if (!fits[row]) {
      have_previous = false;  // the data cannot carry this order: a gap in the chart
      continue;
    }
    const std::vector<PoleInfo> poles = pole_table(fits[row]->fit);
    chart.orders.push_back(p);
    for (const auto& q : poles) {
      if (s.fmax_hz > 0 && q.freq_hz > s.fmax_hz) continue;
      StabilizationPole sp{p, q.freq_hz, q.damping_ratio, PoleStability::New};
      if (have_previous) {
        for (const auto& r : previous) {
          const double df = std::abs(q.freq_hz - r.freq_hz) / std::max(r.freq_hz, 1e-300);
          if (df > s.freq_tol) continue;
          const double dz = std::abs(q.damping_ratio - r.damping_ratio) /
                            std::max(std::abs(r.damping_ratio), 1e-300);
          if (dz <= s.damping_tol) {
            sp.stability = PoleStability::Stable;
            break;
          }
          sp.stability = PoleStability::StableFrequency;
        }
      }
      chart.poles.push_back(sp);
    }
    previous = poles;
    have_previous = true;
  }
  return chart;
}

}  // namespace piezo::dsp
