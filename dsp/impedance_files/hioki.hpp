#pragma once
// HIOKI IM3570 / IM3536 / IM7580 (and the other IM35xx/IM75xx analyzers) CSV as
// the instrument saves a sweep to USB memory: quoted key/value lines of the
// settings first ("MODEL","IM3570" ...), every field in double quotes, CR LF,
// then the header
//   "No.","FREQUENCY(Hz)","Z[Ω]","X[Ω]"
// and one row per point with engineering numbers ("982.8809E+00"). The two
// parameters are the ones chosen on the instrument (Z, Y, θ, Rs, Rp, X, G, B,
// Cs, Cp, Ls, Lp, D, Q; Rdc is not an impedance); a parameter set to OFF has
// the header "OFF" and empty fields. The file is Shift-JIS: Ω is 0x83 0xB6, θ
// 0x83 0xC6, ° 0x81 0x8B, µ 0x83 0xCA; any non-ASCII bytes in a unit position
// are read as the unit the parameter has (Ω for Z, Rs, Rp, X; degrees for θ).
// The layout is the one reported in issue 39 from a real IM3570 file; the
// other parameter names follow HIOKI's manuals (not all seen in a real file).
// Z follows from the two parameters by lcr_parameters.hpp: |Z| with X assumes
// R >= 0, |Z| alone gives |Z| only (a note says which). HIOKI's Z and Y are
// magnitudes, θ the phase of Z. The separator may also be ';' or tab (decimal
// commas then allowed).
// Refused with the file, the line and what is missing: no header, a parameter
// pair that gives neither Z nor |Z| (G alone, θ alone, θ with D).
#include <istream>
#include <string>
#include <vector>

#include "dsp/impedance_files/imported_impedance.hpp"
#include "dsp/impedance_files/text.hpp"

namespace piezo::dsp {

ImportedImpedance read_hioki_csv(std::istream& in, const std::string& name);

namespace zfiles {
ImportedImpedance read_hioki_csv(const std::vector<TextLine>& lines, const std::string& name);
// A HIOKI header line: "No." then "FREQUENCY(Hz)" (quotes optional, any case).
bool hioki_header(std::string_view line);
}  // namespace zfiles

}  // namespace piezo::dsp
