#pragma once
// Where a misfit lies: the frequency axis cut into the regions a transducer
// engineer reads an impedance by — the capacitive band below the first
// resonance, the neighbourhood of each resonance and anti-resonance (±3
// half-power half-widths of the model's damping, split at the midpoint where
// neighbours overlap), the bands between modes and the high-frequency tail —
// each with its share of χ² and the kind of misfit, from a weighted least-
// squares decomposition of the residual ln(Z_meas/Z_model) on four shapes:
// a frequency shift (−∂lnZ/∂ln f), a change of the damping (peak width and
// height), a level (real constant) and a phase (imaginary constant).
#include <optional>
#include <string>
#include <vector>

#include "update/gap_fit.hpp"
#include "update/residual_regions.hpp"

namespace piezo::update {

struct GapRegion {
  std::string name;  // "capacitive band", "resonance 1", "anti-resonance 1", "between 1 and 2", "high-frequency tail"
  double f_lo_hz = 0, f_hi_hz = 0;
  int points = 0;
  double chi2 = 0;       // base fit, this region
  double share = 0;      // of the total χ²
  double excess = 0;     // χ² − 2·points (what the noise does not explain)
  std::string kind;      // dominant: "frequency shift", "peak width/height", "level", "phase", or "noise"
  double shift_pct = 0, width_pct = 0, level_db = 0, phase_deg = 0;
  // The output-error diagnosis's regions (update/residual_regions.hpp): the
  // window's chance under noise, the phase slope's delay, the extra resonance
  // when that is the kind, and the one phrase every view shows.
  double log10_p = 0, delay_s = 0;
  std::optional<ExtraResonance> resonance;
  std::string description;
};

// The located regions of update/residual_regions.hpp as GapRegions, named
// "residual region i" or, found in held-out data, "held-out region i".
std::vector<GapRegion> located_gap_regions(const std::vector<ResidualRegion>& regions, bool heldout);
// The verdict's sentence on them: " The <lead> stands above the noise in
// <description>; and in <description>." and, when one is an extra resonance,
// what such a resonance is. Empty for no region.
std::string located_sentence(const std::vector<GapRegion>& regions, const std::string& lead);

// Regions of the misfit of model `m` at `x` against `d`.
std::vector<GapRegion> gap_regions(const GapModel& m, const GapData& d, const std::vector<double>& x);

}  // namespace piezo::update
