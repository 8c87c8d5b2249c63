#pragma once
// Pure formatters of an ImpedanceResult: CSV (f_hz,re_ohm,im_ohm) and Touchstone
// 1-port (.s1p) in Z format, real/imaginary. Touchstone 1.x stores Z-parameters
// normalised to the reference resistance R given in the option line.
#include <iosfwd>

#include "dsp/impedance_types.hpp"
#include "dsp/uncertainty.hpp"

namespace piezo::dsp {

void write_impedance_csv(std::ostream& os, const ImpedanceResult& r);
// With the uncertainty band (same grid): f_hz,re_ohm,im_ohm first, then
// abs_ohm,abs_sigma_ohm,phase_deg,phase_sigma_deg,coverage_factor — readers of
// the three-column form keep working on the first three.
void write_impedance_csv(std::ostream& os, const ImpedanceResult& r, const ImpedanceBand& band);
void write_touchstone_s1p(std::ostream& os, const ImpedanceResult& r, double reference_ohm = 50.0);

}  // namespace piezo::dsp
