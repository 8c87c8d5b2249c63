#pragma once
// The results file of headless replay ("piezo-replay/1"): one HDF5 file that
// collects, per replayed capture, the input's path and SHA-256, the status,
// the pipeline's JSON report and the impedance curves. It lives beside
// capture_file.hpp because every HDF5 call of the project lives in
// acquisition/; what goes into a record is decided by the caller (jobs/replay).
//
// Layout (all strings UTF-8, variable length):
//   /                     format = "piezo-replay", format_version = 1, software, created_utc
//   /results/KEY          one group per capture; KEY is chosen by the caller
//                         (jobs/replay derives it from path + SHA-256, so shards merge by name)
//     attrs   input_path, sha256, status ("ok" | "failed"), elapsed_s, replayed_utc
//     result_json         scalar string dataset: the JSON report (ok) or the error (failed)
//     curves/NN           attr label; datasets f_hz [N] float64, z_ohm [N, 2] float64 (re, im)
//
// Crash safety, as for shots in capture files: a record is built as an
// anonymous group and linked under /results only when complete, then the file
// is flushed and fsync'ed. A run killed between records leaves every finished
// record readable. Files use the oldest HDF5 format that holds them (no
// "file open for writing" flag that would refuse the file after a kill).
#include <complex>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace piezo::acq {

inline constexpr std::string_view kResultsFormatName = "piezo-replay";
inline constexpr std::int64_t kResultsFormatVersion = 1;

struct StoredCurve {
  std::string label;
  std::vector<double> f_hz;
  std::vector<std::complex<double>> z_ohm;
};

struct ResultRecord {
  std::string key;  // group name under /results: [A-Za-z0-9_-]+
  std::string input_path;
  std::string sha256;  // hex, of the input file's bytes
  std::string status;  // "ok" | "failed"
  std::string result_json;
  double elapsed_s = 0;
  std::string replayed_utc;         // set by put() when empty
  std::vector<StoredCurve> curves;  // read only when asked for
};

// Reading: ResultsError (a CaptureError-like message naming the file, the path
// inside it and the problem) for a file that is not piezo-replay/1.
class ResultsError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct ResultsReadOptions {
  bool load_curves = false;
};

// Calls `fn` for every record, in key order; one record in memory at a time.
void for_each_result(const std::filesystem::path& file,
                     const std::function<void(const ResultRecord&)>& fn,
                     const ResultsReadOptions& opt = {});

// Opens a results file for appending (creates it when absent). Refuses a file
// of another format, or one another process has open for writing.
class ResultsFile {
 public:
  static ResultsFile open_or_create(const std::filesystem::path& file, const std::string& software);
  // A new file (fails if it exists); used by merge through a temporary name.
  static ResultsFile create(const std::filesystem::path& file, const std::string& software);

  ResultsFile(ResultsFile&&) noexcept;
  ResultsFile& operator=(ResultsFile&&) noexcept;
  ~ResultsFile();

  struct IndexEntry {
    std::string key, input_path, sha256, status;
  };
  // Every record's identity and status (no JSON, no curves), in key order.
  std::vector<IndexEntry> index() const;
  // One record (std::nullopt when absent).
  std::optional<ResultRecord> get(const std::string& key, const ResultsReadOptions& opt = {}) const;

  // Writes `rec` as one unit (replacing a record of the same key), flushes and fsyncs.
  void put(const ResultRecord& rec);
  // Removes a record (a stale result of a file that has changed since); flushes.
  void remove(const std::string& key);
  // Copies the records `keys` of results file `src` (opened read-only once),
  // each replacing a record of the same key; flushes and fsyncs at the end.
  void copy_from(const std::filesystem::path& src, const std::vector<std::string>& keys);
  void close();
  const std::filesystem::path& path() const;

 private:
  struct Impl;
  explicit ResultsFile(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace piezo::acq
