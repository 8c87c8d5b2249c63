#pragma once
// Test support (issue 21): simulated cases whose cause is NOT in the effect
// catalogue (model/effects.hpp), for validating that the gap diagnosis answers
// "unexplained" instead of a false name. Each case is an existing SimSpec with
// ONE out-of-catalogue cause added (acq::UnmodelledEffects, or the truth's
// material class); the catalogue effects of the base are left as they are.
//
//   parasitic_branch        a series R-L-C branch across the terminals at a
//                           frequency f inside the measured band and AWAY from
//                           the tube's modes, k_eff 0.05-0.12, Q 40-200
//                           (acquisition/parasitic_branch.hpp)
//   transversely_isotropic  the truth keeps the preset's full 4mm-class
//                           constants (sE13, sE33, sE44, d33, d15, εT11 of
//                           APC850, a PZT-5A-class ceramic) with the base's
//                           four overrides; the fit's class is isotropic
//   wall_thickness          the true wall ±3 % of the declared one (inner
//                           diameter kept): the plan must declare
//                           base.geometry (the defaults on both sides do)
//   acoustic_load           fluid on the outer surface, Z_a = 3-15 % of
//                           water's 1.48e6 Pa·s/m (model/outer_surface_damping.hpp)
//
// Each comes with where it shows: the branch's f ± f/Q; for the acoustic load
// the electrically active modes it damps most (added damping ratio
// c_a/(2ω) ≥ half the largest); for the others the band of the active modes.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "acquisition/sim_setup.hpp"
#include "model/material_presets.hpp"
#include "tests/support/sim_truth.hpp"

namespace piezo::test {

enum class OocKind { parasitic_branch, transversely_isotropic, wall_thickness, acoustic_load };

inline const char* to_string(OocKind k) {
  switch (k) {
    case OocKind::parasitic_branch:
      return "parasitic_branch";
    case OocKind::transversely_isotropic:
      return "transversely_isotropic";
    case OocKind::wall_thickness:
      return "wall_thickness";
    default:
      return "acoustic_load";
  }
}

struct OocCase {
  acq::SimSpec spec;
  OocKind kind = OocKind::parasitic_branch;
  std::string description;
  double band_lo_hz = 0, band_hi_hz = 0;  // where the cause shows
};

// The 36-transducer study's transducer (tests/update/test_gap_validation.cpp,
// draw_cases/run_case): APC850's isotropic class with YE11, nu12, d31, εT33
// each scaled by 1 ± 12 %, Rayleigh β in [0.5, 1.5]e-7 s, noise 1-5 %, no
// catalogue effect. Drawn from `seed` the same way (uniform factors).
inline acq::SimSpec study_transducer(std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  acq::SimSpec s;
  s.noise_rel = 0.01 + 0.04 * u(rng);
  double scale[4];
  for (double& x : scale) x = 1 + 0.24 * (u(rng) - 0.5);
  const auto p = model::isotropic_params(model::find_preset("apc850").material);
  char set[200];
  std::snprintf(set, sizeof set, "YE11=%.6g,nu12=%.6g,d31=%.6g,epsT33_rel=%.6g", p.y_e11 * scale[0],
                p.nu12 * scale[1], p.d31 * scale[2], p.eps_t33 / model::kEps0 * scale[3]);
  s.isotropic = true;
  s.set = set;
  s.damping = {0.0, 0.5e-7 + 1e-7 * u(rng)};
  s.seed = seed;
  return s;
}

namespace detail {
struct ActiveMode {
  double f_hz, coupling, radiation_zeta;
};
// The elastic modes of the true tube of `spec` with their coupling p²/(ω²C0).
inline std::vector<ActiveMode> port_modes(const acq::SimSpec& spec) {
  const auto port = sim_port(spec);
  std::vector<ActiveMode> m;
  for (const auto& pm : port.modes)
    if (!pm.residual && pm.omega > 0)
      m.push_back({pm.omega / (2 * M_PI),
                   pm.participation * pm.participation / (pm.omega * pm.omega * port.c_clamped),
                   pm.radiation_damping / (2 * pm.omega)});
  return m;
}
// Band of the electrically active modes (coupling > 1e-3) inside [lo, hi], ±3 %.
inline std::pair<double, double> active_band(const std::vector<ActiveMode>& modes, double lo,
                                             double hi) {
  double a = std::numeric_limits<double>::infinity(), b = 0;
  for (const auto& m : modes)
    if (m.coupling > 1e-3 && m.f_hz >= lo && m.f_hz <= hi)
      a = std::min(a, m.f_hz), b = std::max(b, m.f_hz);
  if (!(b > 0)) throw std::runtime_error("out_of_catalogue_case: no active mode in the band");
  return {0.97 * a, 1.03 * b};
}
}  // namespace detail

// One case of `kind` on top of `base`, drawn from `seed`; [band_lo_hz,
// band_hi_hz] is the measured band (the pipeline's 100 Hz-120 kHz).
inline OocCase out_of_catalogue_case(OocKind kind, std::uint64_t seed, const acq::SimSpec& base,
                                     double band_lo_hz = 100.0, double band_hi_hz = 120e3) {
  std::mt19937_64 rng(seed * 0x9E3779B97F4A7C15ull + static_cast<std::uint64_t>(kind));
  std::uniform_real_distribution<double> u(0, 1);
  OocCase c;
  c.spec = base;
  c.kind = kind;
  char text[300];
  switch (kind) {
    case OocKind::parasitic_branch: {
      // f in [max(band_lo, 10 kHz), 0.9·band_hi], at least 5 kHz and 10 % from
      // every mode of the bare tube that shows in the impedance at all
      // (coupling > 1e-4, a decade below the "active" threshold).
      const auto modes = detail::port_modes(base);
      const double lo = std::max(band_lo_hz, 10e3), hi = 0.9 * band_hi_hz;
      double f = 0;
      for (int tries = 0; tries < 10000 && f == 0; ++tries) {
        const double x = lo + (hi - lo) * u(rng);
        bool clear = true;
        for (const auto& m : modes)
          if (m.coupling > 1e-4 && std::abs(x - m.f_hz) < std::max(5e3, 0.1 * m.f_hz))
            clear = false;
        if (clear) f = x;
      }
      if (f == 0)
        throw std::runtime_error("out_of_catalogue_case: no frequency clear of the modes");
      const acq::ParasiticResonance r{f, 0.05 + 0.07 * u(rng), 40.0 + 160.0 * u(rng)};
      c.spec.unmodelled.parasitic_branches.push_back(r);
      c.band_lo_hz = f * (1 - 1 / r.q);
      c.band_hi_hz = f * (1 + 1 / r.q);
      std::snprintf(text, sizeof text,
                    "parasitic R-L-C branch across the terminals: f %.0f Hz, k_eff %.3f, Q %.0f",
                    r.f_hz, r.k_eff, r.q);
      break;
    }
    case OocKind::transversely_isotropic: {
      c.spec.isotropic = false;
      std::tie(c.band_lo_hz, c.band_hi_hz) =
          detail::active_band(detail::port_modes(c.spec), band_lo_hz, band_hi_hz);
      std::snprintf(text, sizeof text,
                    "transversely isotropic truth (%s, full 4mm-class constants%s%s) under the "
                    "isotropic fit class",
                    base.material.c_str(), base.set.empty() ? "" : ", overrides ",
                    base.set.c_str());
      break;
    }
    case OocKind::wall_thickness: {
      const double rel = u(rng) < 0.5 ? -0.03 : 0.03;
      c.spec.unmodelled.wall_thickness_rel = rel;
      std::tie(c.band_lo_hz, c.band_hi_hz) =
          detail::active_band(detail::port_modes(c.spec), band_lo_hz, band_hi_hz);
      std::snprintf(text, sizeof text,
                    "wall thickness %+.0f %% of the declared one (inner diameter kept)", 100 * rel);
      break;
    }
    case OocKind::acoustic_load: {
      c.spec.unmodelled.acoustic_impedance_pa_s_m = (0.03 + 0.12 * u(rng)) * 1.48e6;
      const auto modes = detail::port_modes(c.spec);
      double zmax = 0;
      for (const auto& m : modes)
        if (m.coupling > 1e-3 && m.f_hz >= band_lo_hz && m.f_hz <= band_hi_hz)
          zmax = std::max(zmax, m.radiation_zeta);
      double a = std::numeric_limits<double>::infinity(), b = 0;
      std::string which;
      for (const auto& m : modes)
        if (m.coupling > 1e-3 && m.f_hz >= band_lo_hz && m.f_hz <= band_hi_hz &&
            m.radiation_zeta >= 0.5 * zmax) {
          a = std::min(a, m.f_hz), b = std::max(b, m.f_hz);
          char one[80];
          std::snprintf(one, sizeof one, " %.0f Hz (+%.4f)", m.f_hz, m.radiation_zeta);
          which += one;
        }
      if (!(b > 0)) throw std::runtime_error("out_of_catalogue_case: no active mode in the band");
      c.band_lo_hz = 0.97 * a;
      c.band_hi_hz = 1.03 * b;
      std::snprintf(text, sizeof text,
                    "acoustic load on the outer surface, Z_a %.3g Pa·s/m; most damped modes (added "
                    "damping ratio):%s",
                    c.spec.unmodelled.acoustic_impedance_pa_s_m, which.c_str());
      break;
    }
  }
  c.description = text;
  return c;
}

}  // namespace piezo::test
