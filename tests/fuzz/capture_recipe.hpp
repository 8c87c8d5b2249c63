#pragma once
// Structure-aware input for the capture-reader harness: fuzz bytes are a
// recipe that writes a piezo-capture/1 file through the HDF5 C API (so the
// fuzzer explores the reader's validation, not libhdf5's parser of corrupt
// bytes), and alongside it what ../shared/capture-format.md says a reader
// must make of that file.
//
// The recipe chooses: root attributes, the /setup and /shots objects (group,
// missing, dataset, dangling link, ...), attribute types (float64/32 either
// byte order, integers, strings fixed or variable, compounds), shapes
// (scalar, [1], [2], null) and values (NaN, Inf, huge, zero, negative, empty
// or padded strings, missing), the number and names of shots, and per shot
// the dtype, rank, length, storage layout (contiguous, chunked, compact,
// compressed, never written = fill value) and sample values of v1 and v2.
// A zero byte always means the ordinary, valid choice: an empty input (or
// one that runs out) describes a valid one-shot capture.
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "tests/fuzz/fuzz_support.hpp"

namespace piezo::fuzz {

// What the format document says of a choice: a reader must accept it
// (Valid), must refuse it (Invalid), or the document does not decide
// (Unknown: no expectation, e.g. a float32-typed R1 or an alias link).
enum class Verdict { Valid, Unknown, Invalid };
inline Verdict worst(Verdict a, Verdict b) { return a > b ? a : b; }

struct ExpectedShot {
  std::string name;                 // six digits
  Verdict attrs = Verdict::Valid;   // visible without reading samples (types, shapes, lengths)
  Verdict samples = Verdict::Valid; // the sample values (NaN / Inf)
  Verdict load_rules = Verdict::Valid;  // role "load" and its load_ohm (attributes, kept apart:
                                        // see known issue KI-1 in fuzz_capture.cpp)
  // What a correct reader returns for the shot when it accepts it (unset: not predicted).
  std::optional<double> rate;
  std::optional<std::string> excitation, role;
  std::optional<std::int64_t> pretrigger;
  std::optional<std::size_t> n;
  std::optional<std::vector<double>> v1, v2;
  Verdict overall() const { return worst(worst(attrs, load_rules), samples); }
};

struct ExpectedCapture {
  Verdict file = Verdict::Valid;  // root attributes, /setup, /shots itself
  std::optional<double> r1;
  std::vector<ExpectedShot> shots;  // every six-digit member of /shots, sorted by name
  bool members_known = true;        // false: /shots is not the group we filled
  std::string notes;                // what the recipe did, for finding reports
};

// Writes the file the recipe describes to `path` and returns the expectation.
// Returns nullopt when the recipe asks for something HDF5 itself refuses to
// write (not a finding: there is no file to read).
// `allow_huge`: may declare signals of up to 2^40 samples (chunked, never
// written, so the file stays small); only safe where an oversized allocation
// is caught before it happens (libFuzzer's -malloc_limit_mb).
std::optional<ExpectedCapture> write_capture_recipe(ByteReader& r, const std::filesystem::path& path,
                                                    bool allow_huge);

}  // namespace piezo::fuzz
