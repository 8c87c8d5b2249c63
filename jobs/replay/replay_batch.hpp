#pragma once
// Headless replay of many captures: each goes through jobs::run_pipeline (the
// same code as the GUI and the demo) with PipelineRequest::replay_capture set;
// its record goes to the results file (acquisition/results_file.hpp) and,
// optionally, a JSON line and a report folder.
//
// Workers are processes (forked copies of this one, --jobs of them): a
// capture that crashes its worker — libhdf5 on a damaged file, which we
// cannot fix — or hangs it past capture_timeout_s costs that capture only. It
// is recorded as failed (error kind "crashed" or "hung", a message naming the
// file and, when the worker was reading it, the HDF5 library), a new worker
// takes the next capture, and the batch ends with exit 2. Each worker has its
// own copy of libhdf5, so reading no longer serialises on one global lock.
// The batch process alone owns the results file: workers send each record
// back over a pipe (record_wire.hpp), so records are appended without
// inter-process locking or a merge step.
//
// Resume: a capture whose key (path + SHA-256, replay_record.hpp) is already
// in the results file with status "ok" is skipped, and so is one that crashed
// or hung a worker (the same bytes would again); other failures are retried;
// a record of the same path with another digest (the file changed) is
// replaced.
#include <atomic>
#include <cstddef>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "jobs/replay/discover.hpp"
#include "jobs/report/limits.hpp"
#include "jobs/report/lot_summary.hpp"
#include "update/output_error.hpp"

namespace piezo::jobs::replay {

struct ReplayOptions {
  std::vector<std::string> inputs;  // files and folders
  std::filesystem::path out;        // the results file (created or resumed)
  std::size_t jobs = 1;
  ShardSpec shard;
  std::optional<std::filesystem::path> report_dir;
  std::optional<std::filesystem::path>
      jsonl;             // one line per capture of this run (truncated at start)
  std::string material;  // nominal model; empty: the capture's /setup/material, else apc850
  bool isotropic = true;
  update::OeOptions oe_options;  // jobs::PipelineRequest::oe_options (the chain's tolerances)
  bool seed_chain = false;  // also run the seed's CMCM/LM chain (jobs::PipelineRequest::seed_chain)
  // Each capture's held-out capture, by name in the capture's folder: "{stem}"
  // stands for the capture's file name without ".h5" (the refsim corpus:
  // "holdout.h5"; piezobench's own demo/measure pairs: "{stem}-heldout.h5").
  // Empty: piezobench's own pairs and files named holdout/heldout (see
  // effective_holdout_patterns). Missing, or the capture itself: none. A file
  // that is another capture's held-out partner is not a tube: it is not
  // replayed on its own (ReplaySummary::heldout_partners; issue 41).
  std::string holdout;
  std::string software = "piezobench replay";
  // A capture whose worker has not answered after this long is a hang: the
  // worker is killed and the capture recorded as failed ("hung").
  double capture_timeout_s = 600.0;
  // Acceptance limits (jobs/report/limits.hpp): each record gets a "limits"
  // object (pass / fail / error and the reasons) in the results file and its
  // JSON line, and the run ends with the lot summary of the whole results
  // file (ReplaySummary::lot; lot.md, lot.json and the histograms in report_dir).
  std::optional<report::Limits> limits;
};

struct ReplayProgress {
  std::size_t total = 0;  // captures of this shard
  std::size_t done = 0;   // replayed + failed + skipped
  std::size_t ok = 0, failed = 0, skipped = 0;
  std::size_t failed_before = 0;  // of the skipped: captures that crashed or hung a worker before
  double rate_per_s = 0;  // captures replayed (not skipped) per second of wall time
  double eta_s = -1;      // < 0: unknown yet
};

struct ReplayIssue {
  std::string path, kind, message;  // kind: bad capture | bad input | failed | report
};

struct ReplaySummary {
  std::size_t found = 0;  // captures under the inputs (all shards), held-out partners included
  // Of `found`: files that are another capture's held-out partner (by the
  // holdout pattern), used by that capture's diagnosis and not replayed as tubes.
  std::size_t heldout_partners = 0;
  ReplayProgress counts;  // of this shard
  double wall_s = 0;
  bool interrupted = false;
  std::vector<ReplayIssue> issues;  // failed captures and report write errors, in order
  std::size_t report_errors = 0;
  std::optional<report::LotSummary> lot;  // with ReplayOptions::limits
};

struct ReplayCallbacks {
  std::function<void(const ReplayProgress&)> progress;  // after each capture, in the batch process
  std::function<void(const ReplayIssue&)> issue;        // as it happens
};

// The held-out patterns a replay tries, first match wins: `holdout` alone
// when given; else piezobench's own pairs ("{stem}-heldout.h5", written by
// `measure`/`demo` with /setup/heldout_of) and a file named for what it is
// ("{stem}-holdout.h5", "holdout.h5", "heldout.h5" beside the capture).
std::vector<std::string> effective_holdout_patterns(const std::string& holdout);

// The held-out capture of `file` by the first of `patterns` that names an
// existing file other than `file` itself.
std::optional<std::filesystem::path> heldout_partner(const std::filesystem::path& file,
                                                     const std::vector<std::string>& patterns);

// The captures of `all` that are not another one's held-out partner (order kept),
// and how many were left out.
std::vector<std::filesystem::path> without_heldout_partners(const std::vector<std::filesystem::path>& all,
                                                            const std::vector<std::string>& patterns,
                                                            std::size_t* left_out);

// Throws std::invalid_argument for bad options or inputs, acq::ResultsError for
// a results file that cannot be used, std::runtime_error when the results file
// cannot be written (the batch stops: every finished record is kept).
ReplaySummary run_replay(const ReplayOptions& opt, const ReplayCallbacks& cb,
                         const std::atomic<bool>& cancel);

// report_dir/index.html of everything in a results file (report/index_html.hpp).
void write_index(const std::filesystem::path& results, const std::filesystem::path& report_dir);

// The batch summary of everything in a results file (report/batch_summary.hpp).
void write_batch_summary(const std::filesystem::path& results,
                         const std::filesystem::path& report_dir);

// The lot summary of every record in a results file against `limits`
// (each record judged afresh, whatever its stored "limits" object says).
report::LotSummary summarize_lot_file(const std::filesystem::path& results, const report::Limits& limits);

}  // namespace piezo::jobs::replay
