#pragma once
// The one owner of the piezo-capture/1 HDF5 schema: path constants, version
// check, validation on read, atomic shot-by-shot writing. Every HDF5 call of
// the project lives in acquisition/.
#include <filesystem>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "acquisition/capture.hpp"

namespace piezo::acq {

struct ReadOptions {
  // Strict (default): any invalid shot refuses the whole file. Lenient: an
  // invalid shot is left out and its message goes to Capture::rejected_shots;
  // file-level problems still refuse the file.
  bool skip_invalid_shots = false;
  // Read the signals (false: attributes only, v1/v2 left empty but checked for shape/type).
  bool load_samples = true;
};

// Reads and validates a capture. Throws CaptureError (file, path inside, problem).
// Unknown groups and attributes are ignored, /truth included.
Capture read_capture(const std::filesystem::path& file, const ReadOptions& opt = {});

struct WriterOptions {
  std::string software;  // written to the `software` attribute
  bool overwrite = false;  // replace an existing file under the final name
};

// Writes a capture atomically: everything goes to `<final>.partial` in the same
// folder; each appended shot is written as one unit (an anonymous group linked
// under /shots only once complete), flushed and fsync'ed, so the partial file
// always holds every completed shot; close() renames it to the final name.
// If the writer is destroyed without close() (an error unwinding the stack,
// a cancelled measurement) it still closes and renames: acquired shots are kept.
class CaptureWriter {
 public:
  CaptureWriter(std::filesystem::path final_path, const Setup& setup, const WriterOptions& opt = {});
  ~CaptureWriter();
  CaptureWriter(const CaptureWriter&) = delete;
  CaptureWriter& operator=(const CaptureWriter&) = delete;

  // Validates, writes and flushes one shot; returns its name ("000007").
  std::string append(const Shot& shot);
  void close();

  // Simulated captures only: ground truth under /truth, as attributes. No
  // estimator, updater or diagnosis reads it (the reader ignores the group).
  // `series` are 1-D double attributes (one value per shot, e.g. the
  // disturbances each shot got). A name written again replaces the old value.
  void write_truth(const std::vector<std::pair<std::string, double>>& numbers,
                   const std::vector<std::pair<std::string, std::string>>& strings = {},
                   const std::vector<std::pair<std::string, std::vector<double>>>& series = {});

  std::size_t shots_written() const;
  const std::filesystem::path& final_path() const;
  const std::filesystem::path& partial_path() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Convenience: write a whole capture (used by tests, fixtures and exports).
void write_capture(const std::filesystem::path& file, const Capture& cap,
                   const WriterOptions& opt = {});

std::filesystem::path partial_path_for(const std::filesystem::path& final_path);

}  // namespace piezo::acq
