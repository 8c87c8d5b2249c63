#include "acquisition/parasitic_branch.hpp"

#include <cmath>
#include <stdexcept>

namespace piezo::acq {

ParasiticBranch parasitic_branch(const ParasiticResonance& r, double c_tube_f) {
  if (!(r.f_hz > 0) || !std::isfinite(r.f_hz))
    throw std::invalid_argument("parasitic_branch: f_hz must be > 0");
  if (!(r.k_eff > 0 && r.k_eff < 1))
    throw std::invalid_argument("parasitic_branch: k_eff must be in (0, 1)");
  if (!(r.q > 0) || !std::isfinite(r.q))
    throw std::invalid_argument("parasitic_branch: q must be > 0");
  if (!(c_tube_f > 0))
    throw std::invalid_argument("parasitic_branch: the tube capacitance must be > 0");
  const double k2 = r.k_eff * r.k_eff, w = 2.0 * M_PI * r.f_hz;
  ParasiticBranch b;
  b.c_f = c_tube_f * k2 / (1.0 - k2);        // k² = C/(C + C_t)
  b.l_h = 1.0 / (w * w * b.c_f);             // ω_s² = 1/(LC)
  b.r_ohm = std::sqrt(b.l_h / b.c_f) / r.q;  // Q = √(L/C)/R
  return b;
}

}  // namespace piezo::acq
