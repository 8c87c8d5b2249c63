#pragma once
// HP/Agilent 4294A text export (the analyzer's "save data as ASCII"): a model
// line ("4294A REV1.11"), quoted settings ("MEASURE PARAMETER: IMPEDANCE MAG
// PHASE (DEG)", "NUMBER of POINTS: 801", ...), then per trace "TRACE: A",
// "FORMAT: LOG", a quoted column header ("Frequency" "Data Trace Real" "Data
// Trace Imag", possibly "Memory Trace Real" "Memory Trace Imag") and
// tab-separated rows. Trace A holds the first quantity of the measurement
// parameter, trace B the second; both are read from the "Data Trace Real"
// column (the imaginary column is 0 for the scalar display formats) and
// combined into Z:
//   IMPEDANCE / ADMITTANCE MAG PHASE (DEG or RAD), |Z|-θ, |Y|-θ,
//   IMPEDANCE / ADMITTANCE REAL IMAG, R-X, G-B,
//   Cs, Ls with Rs, D or Q; Cp, Lp with G, Rp, D or Q.
// The MAG PHASE forms are those of the three EQCIRC3 files (fixtures/eqcirc3);
// the wording of the others is our reading of the parameter names.
// Memory columns are ignored; a trace with a non-zero imaginary column (a
// complex display format) is refused with the reason.
#include <istream>
#include <string>
#include <vector>

#include "dsp/impedance_files/imported_impedance.hpp"
#include "dsp/impedance_files/text.hpp"

namespace piezo::dsp {

ImportedImpedance read_hp4294a_text(std::istream& in, const std::string& name);

namespace zfiles {
ImportedImpedance read_hp4294a_text(const std::vector<TextLine>& lines, const std::string& name);
}

}  // namespace piezo::dsp
