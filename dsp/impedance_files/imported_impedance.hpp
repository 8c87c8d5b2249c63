#pragma once
// What every reader of dsp/impedance_files/ returns: Z(f) from a file written by
// an impedance analyzer, a VNA or a script, on an ascending grid, with what the
// file held (format, quantity) and what the reader had to assume (notes).
// Readers are pure: they parse a std::istream and never touch the file system
// (read_any.hpp's read_impedance_file is the one exception, by name).
#include <complex>
#include <cstddef>
#include <limits>
#include <string>
#include <vector>

namespace piezo::dsp {

enum class ImpedanceFileFormat {
  Auto,        // as a hint: detect from the content (read_any.hpp)
  Touchstone,  // Touchstone 1.x / 2.0 one-port (.s1p, .ts)
  Hp4294a,     // HP/Agilent 4294A text export ("TRACE: A" / "TRACE: B")
  E4990a,      // Keysight E4990A CSV (BEGIN CHn_DATA ... END)
  Bode100,     // OMICRON Bode 100 (Bode Analyzer Suite) CSV
  Table,       // any delimited table with a header (f and a pair of Z or Y columns)
  Hioki,       // HIOKI IM3570 / IM3536 / IM7580 CSV ("No.","FREQUENCY(Hz)",two parameters)
  LabOne,      // Zurich Instruments LabOne sweeper / impedance-analyzer CSV or TXT export
};

// "touchstone", "hp4294a", "e4990a", "bode100", "table", "hioki", "labone" ("auto" for Auto).
const char* to_string(ImpedanceFileFormat f);

struct ImportedImpedance {
  std::vector<double> f_hz;                 // strictly ascending, finite, >= 0
  std::vector<std::complex<double>> z_ohm;  // finite, with a finite |Z|
  // True when the file gives |Z| but not its phase (|Z| alone, |Z| with R, ...):
  // z_ohm then holds |Z| + 0j, and only its magnitude means anything.
  bool magnitude_only = false;
  // Per-point standard uncertainty (1 σ) of |Z| and of arg Z, when the file
  // carries them (the band of dsp/impedance_io's CSV); empty otherwise.
  std::vector<double> abs_sigma_ohm;
  std::vector<double> phase_sigma_rad;
  double coverage_factor = std::numeric_limits<double>::quiet_NaN();  // k of that band

  ImpedanceFileFormat format = ImpedanceFileFormat::Table;
  std::string format_name;         // e.g. "Touchstone 2.0", "HP 4294A text (4294A REV1.11)"
  std::string quantity;            // what the numbers were, e.g. "admittance |Y| and phase (deg)"
  std::vector<std::string> notes;  // assumptions and skipped content, one sentence each

  std::size_t size() const { return f_hz.size(); }
};

}  // namespace piezo::dsp
