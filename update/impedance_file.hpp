#pragma once
// Measured impedance functions from files, and the features the updater
// needs from them (seed §6.4.1): resonances = |Z| minima, anti-resonances =
// |Z| maxima (each refined below the grid by a parabola through the three
// samples around it, in dB), and |Z| at one frequency in the capacitive region.
// The readers are dsp/impedance_files/ (read_any.hpp): Touchstone 1.x/2.0 one-port
// (S, Z or Y), HP 4294A text, Keysight E4990A CSV, Bode 100 CSV and any table
// with a header (f_hz,re_ohm,im_ohm and the rest); the format is found from the
// content. Here a curve must also have at least 5 points.
#include <complex>
#include <istream>
#include <string>
#include <vector>

#include "update/features.hpp"

namespace piezo::update {

struct ImpedanceCurve {
  std::vector<double> f_hz;  // strictly ascending
  std::vector<std::complex<double>> z_ohm;
};

// Throw std::invalid_argument (bad content) or std::runtime_error (cannot open).
// read_impedance_csv and read_impedance_file read any format (detected from the
// content); read_touchstone_s1p insists on Touchstone.
ImpedanceCurve read_impedance_csv(const std::string& path);
ImpedanceCurve read_touchstone_s1p(const std::string& path);
// The same from a stream; `name` stands for the file in messages.
ImpedanceCurve parse_impedance_csv(std::istream& in, const std::string& name);
ImpedanceCurve parse_touchstone_s1p(std::istream& in, const std::string& name);
ImpedanceCurve read_impedance_file(const std::string& path);
void write_impedance_csv(const std::string& path, const ImpedanceCurve& c);

struct FeatureOptions {
  int max_modes = 3;  // resonance/anti-resonance pairs kept (lowest first)
  // Rise from a minimum to the following maximum, and the deepest dip stepped
  // over on the way up (weak inactive modes: 1.5 dB at ζ = 2.5e-4 on our tube).
  double min_prominence_db = 3.0;
  double low_f_fraction = 0.05;  // low-f point at or below this fraction of the first resonance …
  double capacitive_phase_tol_deg = 5.0;  // … where the phase is within this of −90°
};

struct ExtractedFeatures {
  MeasuredFeatures features;
  double low_z_phase_deg = 0;  // phase of Z at the chosen low-frequency point
};

// Throws std::invalid_argument when no resonance pair or no capacitive point is found.
ExtractedFeatures extract_features(const ImpedanceCurve& c, const FeatureOptions& opt = {});

}  // namespace piezo::update
