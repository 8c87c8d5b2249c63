#pragma once
// Test support: writes a valid capture, then damages it in one precise way
// through the HDF5 C API, to exercise every reader validation rule.
#include <filesystem>
#include <ostream>
#include <string>
#include <vector>

#include "acquisition/capture.hpp"

namespace piezo::test {

enum class Defect {
  None,
  MissingFormat,
  WrongFormatName,
  WrongFormatVersion,
  MissingSetup,
  MissingR1,
  ZeroR1,
  NegativeR1,
  ZeroSampleRate,
  NegativeSampleRate,
  MissingSampleRate,
  UnknownExcitation,
  MissingV1,
  MissingV2,
  IntegerDtype,
  StringDtype,
  TwoDimensional,
  LengthMismatch,
  TooShort,
  NaNSample,
  InfSample,
  EmptyShots,
  Truncated,
  NotHdf5,
  OutOfRangeSample,
  TinySampleRate,
  HugeSampleRate,
  AbsurdLength,
  BadAdcBits,
  Directory,
  MissingPath,
};

struct DefectCase {
  Defect defect;
  const char* name;
  const char* h5path;  // path inside the file the error must name
  const char* problem;  // substring of the problem text
};

inline void PrintTo(const DefectCase& c, std::ostream* os) { *os << c.name; }

// Every defect the reader must refuse, with what the error must say.
const std::vector<DefectCase>& all_defects();

// A small valid capture: 2 shots of 64 samples (exp_decay), deterministic data.
acq::Capture small_valid_capture(std::size_t n = 64);

// Writes the valid capture to `file` and applies `d`. For Directory/MissingPath
// it creates a directory / ensures nothing exists at `file`.
void make_capture_with_defect(const std::filesystem::path& file, Defect d);

// Adds things a reader must ignore: a /truth group with attributes, unknown
// attributes on root, setup and shots, and a non-shot member of /shots.
void add_ignorable_extras(const std::filesystem::path& file);

// Removes the /truth group (a simulated capture as a real bench would write it).
// Returns false when the file has no /truth.
bool strip_truth(const std::filesystem::path& file);

}  // namespace piezo::test
