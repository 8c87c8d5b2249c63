#pragma once
// Stabilization chart of the Prony-SS impedance fit: the poles (eq. 164,
// frequency and damping ratio by eq. 165) of the fit at every model order of
// a range, each marked by how it compares with the poles one order step
// below — the view modal analysts use to pick the order (Peeters & De Roeck,
// "Reference-based stochastic subspace identification", MSSP 13, 1999, the
// usual criteria: 1 % in frequency, 5 % in damping).
//   stable       a pole of the lower order within freq_tol and damping_tol
//   stable_freq  within freq_tol only
//   new          neither
// Physical poles persist as the order grows; noise poles wander.
#include <cstddef>
#include <vector>

#include "dsp/prony_impedance.hpp"

namespace piezo::dsp {

struct StabilizationOptions {
  std::size_t min_order = 2, max_order = 30, step = 2;
  double freq_tol = 0.01;     // relative
  double damping_tol = 0.05;  // relative
  double fmax_hz = 0.0;       // poles above are left out of the chart (0: all)
};

enum class PoleStability { New, StableFrequency, Stable };

struct StabilizationPole {
  std::size_t order = 0;
  double freq_hz = 0.0, damping_ratio = 0.0;
  PoleStability stability = PoleStability::New;
};

struct StabilizationChart {
  std::vector<std::size_t>
      orders;  // the orders fitted (an order the data cannot carry is left out)
  std::vector<StabilizationPole> poles;  // Im λ ≥ 0, f ≤ fmax, every order
  std::size_t selected_order = 0;  // the order the automatic rule picks (eqs 162-163), 0 if not run
};

// The chart for the impedance fit of `rec` with `opt` (its order overridden
// per row). Throws std::invalid_argument for a bad range.
StabilizationChart stabilization_chart(const DividerRecord& rec, const PronyImpedanceOptions& opt,
                                       const StabilizationOptions& s = {});

const char* to_string(PoleStability s);

}  // namespace piezo::dsp
