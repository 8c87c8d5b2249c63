#pragma once
// Zurich Instruments LabOne exports of a sweep (MFIA, or an MFLI with the IA
// option): the Sweeper's or the Impedance Analyzer module's "Save" as CSV or
// text. LabOne's native CSV (seen in a real file: dev3221_imps_0_sample_00000.csv
// of an MFLI/MFIA, 35 sweeps) is transposed: a header "chunk;timestamp;size;
// fieldname" padded with ';', then one row per chunk and field
// ("1;1201...;150;realz;v1;v2;..."), frequencies descending, unfinished cells
// empty or nan; the last complete sweep is read (a note names the chunk). Also
// read, one row per point:
//   CSV   ';'-separated, a header such as
//         chunk;timestamp;grid;frequency;realz;imagz;absz;phasez;param0;param1
//         (any order, more columns allowed)
//   text  '%' comment lines first (settings; the last one may be the header),
//         columns separated by ';', ',', tabs or blanks
// Z is read from realz/imagz (ohm), else absz/phasez (ohm, rad: LabOne's
// phases are radians), else param0/param1 when a line of the file states the
// representation ("representation: Cp D", the IA module's two parameters, any
// pair of lcr_parameters.hpp); a note says which. Demodulator columns (x, y, r,
// phase: volts) are not an impedance: such a file is refused with the next
// step. Several sweeps (a chunk column with more than one value): the last is
// read, with a note. Points not measured ("nan") are left out, with a note.
// The row-per-point layouts follow issue 39's description and LabOne's field
// names (realz, imagz, absz, phasez, param0, param1 of the impedance sample);
// they and the representation line have not been seen in a real file.
#include <istream>
#include <string>
#include <vector>

#include "dsp/impedance_files/imported_impedance.hpp"
#include "dsp/impedance_files/text.hpp"

namespace piezo::dsp {

ImportedImpedance read_labone(std::istream& in, const std::string& name);

namespace zfiles {
ImportedImpedance read_labone(const std::vector<TextLine>& lines, const std::string& name);
// A LabOne export: a line naming realz/imagz/absz/phasez/param0 or chunk and
// timestamp, or a '%' comment naming LabOne or Zurich Instruments.
bool labone_file(const std::vector<TextLine>& lines);
}  // namespace zfiles

}  // namespace piezo::dsp
