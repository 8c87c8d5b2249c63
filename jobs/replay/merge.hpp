#pragma once
// `replay-merge`: the results files of several shards (or runs) into one.
// Records are copied whole (HDF5 object copy) under their keys, so a merged
// file holds exactly what one unsharded run would have written. A key present
// in several inputs is kept once: the first "ok" record wins over any other
// and over "failed" ones. The output is written under a temporary name and
// renamed when complete.
#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace piezo::jobs::replay {

struct MergeOptions {
  std::vector<std::filesystem::path> inputs;
  std::filesystem::path out;
  bool overwrite = false;
  std::optional<std::filesystem::path> report_dir;  // batch summary of the merged file
  std::optional<std::filesystem::path> jsonl;       // one line per merged record
  std::string software = "piezobench replay-merge";
};

struct MergeSummary {
  std::size_t records = 0;  // in the output
  std::size_t ok = 0, failed = 0;
  std::size_t duplicates = 0;         // records left out because their key was already merged
  std::vector<std::string> warnings;  // e.g. one path with two different digests
};

// Throws acq::ResultsError naming an input that is not a results file,
// std::invalid_argument for bad options; the output is then not created.
MergeSummary merge_results(const MergeOptions& opt);

}  // namespace piezo::jobs::replay
