#include "jobs/replay/replay_batch.hpp"

#include <algorithm>
#include <chrono>
#include <fstream>
#include <map>
#include <set>
#include <cstdio>
#include <stdexcept>

#include "acquisition/capture_file.hpp"
#include "acquisition/contained_read.hpp"
#include "acquisition/results_file.hpp"
#include "jobs/pipeline/pipeline.hpp"
#include "jobs/replay/record_wire.hpp"
#include "jobs/replay/replay_record.hpp"
#include "jobs/replay/sha256.hpp"
#include "jobs/replay/worker_pool.hpp"
#include "jobs/report/batch_summary.hpp"
#include "jobs/report/capture_report.hpp"
#include "jobs/report/index_html.hpp"
#include "jobs/report/lot_report.hpp"
#include "jobs/export/report_export.hpp"
#include "jobs/json/json_text.hpp"
#include "jobs/nominal_material.hpp"
#include "update/output_error/spare_core.hpp"

namespace piezo::jobs::replay {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// A message that names the file (CaptureError's already does).
std::string naming(const std::string& path, const std::string& what) {
  return what.rfind(path, 0) == 0 ? what : path + ": " + what;
}

// What the batch process keeps (one thread; workers send it their outcomes):
// the results file, the JSON lines, counters.
class Sink {
 public:
  Sink(const ReplayOptions& opt, const ReplayCallbacks& cb, std::size_t total)
      : results_(acq::ResultsFile::open_or_create(opt.out, opt.software)), cb_(cb), limits_(opt.limits) {
    counts_.total = total;
    for (auto& e : results_.index()) {
      if (e.status == "ok") done_.emplace(e.key, e.input_path);
      // A capture that crashed or hung a worker would do so again: the same bytes
      // (the key holds the digest) are not retried. Other failures are.
      if (e.status == "failed" && kept_failure(e.key)) failed_done_.insert(e.key);
      by_path_[e.input_path].push_back(e.key);
    }
    if (opt.jsonl) {
      jsonl_.open(*opt.jsonl, std::ios::trunc);
      if (!jsonl_) throw std::invalid_argument("--jsonl: cannot write " + opt.jsonl->string());
    }
  }

  // done_ is only read after construction: no lock needed.
  bool finished(const std::string& key) const {
    return done_.count(key) > 0 || failed_done_.count(key) > 0;
  }

  // A capture finished earlier: its stored line goes to this run's JSON lines.
  void skipped(const std::string& key) {
    if (limits_) {  // judged against this run's limits; the stored verdict follows them
      acq::ResultsReadOptions ro;
      ro.load_curves = true;
      if (auto rec = results_.get(key, ro)) {
        const std::string before = rec->result_json;
        judge(*rec);
        if (rec->result_json != before) results_.put(*rec);
        line(*rec);
      }
    } else if (jsonl_.is_open()) {
      if (auto rec = results_.get(key)) line(*rec);
    }
    ++counts_.skipped;
    if (failed_done_.count(key)) ++counts_.failed_before;
    step();
  }

  void put(acq::ResultRecord rec, const std::optional<ReplayIssue>& issue) {
    judge(rec);
    results_.put(rec);
    // Older records of this path with another digest describe a file that has changed since.
    for (const auto& old : by_path_[rec.input_path])
      if (old != rec.key) results_.remove(old);
    by_path_[rec.input_path] = {rec.key};
    line(rec);
    ++processed_;
    (rec.status == "ok" ? counts_.ok : counts_.failed)++;
    if (issue) report_issue(*issue);
    step();
  }

  void report_issue(const ReplayIssue& i) {
    issues_.push_back(i);
    if (cb_.issue) cb_.issue(i);
  }
  void issue(const ReplayIssue& i) {
    report_issue(i);
  }

  void close() {
    results_.close();
    if (jsonl_.is_open()) jsonl_.close();
  }

  ReplayProgress counts() const { return counts_; }
  std::vector<ReplayIssue> issues() const { return issues_; }

 private:
  void line(const acq::ResultRecord& rec) {
    if (!jsonl_.is_open()) return;
    jsonl_ << jobs::json_text(record_json(rec)) << "\n";
    jsonl_.flush();
  }

  // The record's "limits" object (pass / fail / error and the reasons), in its stored JSON.
  void judge(acq::ResultRecord& rec) const {
    if (!limits_) return;
    auto j = nlohmann::json::parse(rec.result_json, nullptr, false);
    if (!j.is_object()) return;  // record_json() reports it as a bad record
    j.erase("limits");
    j["limits"] = report::verdict_json(*limits_, report::evaluate_record(*limits_, j));
    rec.result_json = jobs::json_text(j);
  }

  void step() {
    ++counts_.done;
    const double t = seconds_since(t0_);
    counts_.rate_per_s = t > 0 ? processed_ / t : 0;
    const std::size_t left = counts_.total - counts_.done;
    counts_.eta_s =
        processed_ > 0 && counts_.rate_per_s > 0 ? left / counts_.rate_per_s : (left ? -1.0 : 0.0);
    if (cb_.progress) cb_.progress(counts_);
  }

  acq::ResultsFile results_;
  const ReplayCallbacks& cb_;
  const std::optional<report::Limits>& limits_;
  std::ofstream jsonl_;
  bool kept_failure(const std::string& key) const {
    const auto rec = results_.get(key);
    if (!rec) return false;
    const auto j = nlohmann::json::parse(rec->result_json, nullptr, false);
    if (!j.is_object() || !j.contains("error") || !j["error"].is_object()) return false;
    const auto kind = j["error"].value("kind", std::string());
    return kind == "crashed" || kind == "hung";
  }

  std::map<std::string, std::string> done_;  // key → path of finished ("ok") records
  std::set<std::string> failed_done_;        // keys of captures that crashed or hung a worker
  std::map<std::string, std::vector<std::string>> by_path_;  // path → keys
  ReplayProgress counts_;
  std::size_t processed_ = 0;
  std::vector<ReplayIssue> issues_;
  Clock::time_point t0_ = Clock::now();
};

// ReplayOptions::holdout for `file`: the named file beside it, if it exists
// and is not the capture itself.
std::optional<fs::path> heldout_for(const fs::path& file, const std::string& pattern) {
  if (pattern.empty()) return std::nullopt;
  std::string name = pattern;
  const std::string stem = file.stem().string();
  for (std::size_t p = name.find("{stem}"); p != std::string::npos; p = name.find("{stem}", p + stem.size()))
    name.replace(p, 6, stem);
  const fs::path ho = file.parent_path() / name;
  std::error_code ec;
  if (!fs::is_regular_file(ho, ec) || fs::equivalent(ho, file, ec)) return std::nullopt;
  return ho;
}

}  // namespace

std::vector<std::string> effective_holdout_patterns(const std::string& holdout) {
  if (!holdout.empty()) return {holdout};
  return {"{stem}-heldout.h5", "{stem}-holdout.h5", "holdout.h5", "heldout.h5"};
}

std::optional<fs::path> heldout_partner(const fs::path& file, const std::vector<std::string>& patterns) {
  for (const auto& p : patterns)
    if (auto ho = heldout_for(file, p)) return ho;
  return std::nullopt;
}

std::vector<fs::path> without_heldout_partners(const std::vector<fs::path>& all,
                                               const std::vector<std::string>& patterns, std::size_t* left_out) {
  std::set<fs::path> partners;
  const std::set<fs::path> present(all.begin(), all.end());
  for (const auto& f : all)
    if (const auto ho = heldout_partner(f, patterns); ho && present.count(ho->lexically_normal()))
      partners.insert(ho->lexically_normal());
  std::vector<fs::path> tubes;
  for (const auto& f : all)
    if (!partners.count(f)) tubes.push_back(f);
  // Every file a partner (a folder of held-out captures alone, or a pattern
  // that pairs each file with another): nothing would be a tube; replay all.
  if (tubes.empty()) tubes = all;
  if (left_out) *left_out = all.size() - tubes.size();
  return tubes;
}

namespace {

// ------------------------------------------------------------- one capture
// Runs in a worker process: everything but the results file. `stage` tells the
// batch what the worker is doing, so that a crash can be named.
Outcome replay_capture(const fs::path& file, const ReplayOptions& opt, const Sink& sink,
                       const std::atomic<bool>& cancel,
                       const std::function<void(const char*, const std::string&)>& stage) {
  const std::string path = file.string();
  const auto t0 = Clock::now();
  Outcome out;
  auto fail = [&](const std::string& sha, const std::string& kind, const std::string& msg) {
    out.record = failed_record(path, sha, kind, msg, seconds_since(t0));
    out.key = out.record.key;
    out.issue = WireIssue{path, kind, msg};
    if (opt.report_dir) {
      try {
        report::write_failed_capture_report(
            {path, sha, "", out.record.elapsed_s, {}, {}}, msg,
            *opt.report_dir / report::capture_report_folder(path, out.key));
      } catch (const std::exception& e) {
        out.report_issue = WireIssue{path, "report", e.what()};
      }
    }
    return out;
  };
  std::string sha;
  try {
    sha = sha256_file(file);
  } catch (const std::exception& e) {
    return fail("", "bad capture", naming(path, e.what()));
  }
  out.key = record_key(path, sha);
  if (sink.finished(out.key)) {
    out.skipped = true;
    return out;
  }
  std::string material = opt.material;
  jobs::PipelineResult result;
  try {
    stage("reading", sha);
    std::optional<std::string> material_warning;
    if (material.empty()) {
      acq::ReadOptions ro;
      ro.load_samples = false;  // attributes only: which nominal model to update
      ro.skip_invalid_shots = true;
      const auto nm = jobs::nominal_material("", acq::read_capture(file, ro).setup.material);
      material = nm.name;
      material_warning = nm.warning;
    }
    stage("processing", sha);
    jobs::PipelineRequest req;
    req.replay_capture = path;
    req.replay_contained = false;  // this worker process is the containment
    req.material = material;
    req.isotropic = opt.isotropic;
    req.seed_chain = opt.seed_chain;
    req.oe_options = opt.oe_options;
    // --jobs workers keep the cores busy already: one thread per fit then.
    if (opt.jobs > 1) req.oe_options.threads = 1;
    if (const auto ho = heldout_partner(file, effective_holdout_patterns(opt.holdout))) {
      req.heldout_capture = ho->string();
      req.heldout_optional = true;
    }
    result = jobs::run_pipeline(req, nullptr, cancel);
    if (material_warning) result.warnings.insert(result.warnings.begin(), *material_warning);
  } catch (const acq::CaptureError& e) {
    return fail(sha, "bad capture", e.what());
  } catch (const std::invalid_argument& e) {
    return fail(sha, "bad input", naming(path, e.what()));
  } catch (const std::exception& e) {
    return fail(sha, "failed", naming(path, e.what()));
  }
  if (cancel) {  // a cancelled pipeline returns a partial result: not a finished capture
    out.cancelled = true;
    return out;
  }
  const double elapsed = seconds_since(t0);
  if (opt.report_dir) {
    try {
      report::CaptureInfo info{path, sha, material, elapsed, {}, {}};
      if (opt.limits) {  // the capture's own PASS/FAIL on its page (the batch stores the same verdict)
        const auto v = report::evaluate_result(*opt.limits, jobs::report_json(result));
        info.limits_status = v.status == "pass" ? "PASS" : v.status == "fail" ? "FAIL" : "ERROR";
        info.limits_reasons = v.reasons;
      }
      report::write_capture_report(result, info, *opt.report_dir / report::capture_report_folder(path, out.key));
    } catch (const std::exception& e) {
      out.issue = WireIssue{path, "report", e.what()};
    }
  }
  out.record = ok_record(path, sha, material, result, elapsed);
  return out;
}

// The batch's side of the worker processes (worker_pool.hpp): a worker replays
// files[i] and sends its outcome (record_wire.hpp); the batch puts outcomes in
// the sink, and records a capture whose worker crashed or hung as failed.
class ReplayWork {
 public:
  ReplayWork(const std::vector<fs::path>& files, const ReplayOptions& opt, Sink& sink,
             const std::atomic<bool>& cancel)
      : files_(files), opt_(opt), sink_(sink), cancel_(cancel) {}

  void run() {
    WorkerPoolCallbacks cb;
    const std::atomic<int>* spare = nullptr;  // (the pool's, set before it forks its workers)
    cb.work = [this, &spare](std::size_t i, const auto& stage) {
      // In the worker: its fit may borrow the core of a sibling that has no
      // capture left (update/output_error/spare_core.hpp; the same answers).
      if (opt_.jobs > 1) update::oe::set_spare_cores(spare);
      // A damaged file must not take the machine's memory (contained_read.hpp);
      // twice its size for a held-out partner beside it.
      std::error_code ec;
      const auto size = std::filesystem::file_size(files_[i], ec);
      acq::limit_memory_for_capture(ec ? 0 : 2 * size);
      return encode_outcome(replay_capture(files_[i], opt_, sink_, cancel_,
                                           [&](const char* what, const std::string& sha) { stage(what, sha); }));
    };
    cb.done = [this](std::size_t, const std::string& payload) { apply(decode_outcome(payload)); };
    cb.lost = [this](const LostTask& t) { lost(t); };
    WorkerPool pool({files_.size(), opt_.jobs, opt_.capture_timeout_s}, std::move(cb), cancel_);
    spare = pool.spare_cores();
    pool.run();
  }

 private:
  void lost(const LostTask& t) {
    const std::string path = files_[t.task].string();
    if (t.kind == "hung") {
      char b[200];
      std::snprintf(b, sizeof b,
                    "replay did not finish within %.0f s (%s); the worker was killed and the "
                    "capture left out",
                    opt_.capture_timeout_s,
                    t.stage == "reading" ? "the HDF5 library hung reading the file" : "hung");
      record_lost(t.task, t.detail, "hung", b, t.elapsed_s);
      return;
    }
    std::string msg =
        t.stage == "reading"
            ? "the HDF5 library crashed reading " + path + " (" + t.how +
                  "): the file is damaged or not a capture; it was left out"
            : "the replay worker died (" + t.how + ") while processing " + path +
                  (t.stage.empty() ? "" : " (stage: " + t.stage + ")") + "; the capture was left out";
    record_lost(t.task, t.detail, "crashed", msg, t.elapsed_s);
  }

  void record_lost(std::size_t i, std::string sha, const std::string& kind,
                   const std::string& msg, double elapsed) {
    const std::string path = files_[i].string();
    if (sha.empty()) {
      try {
        sha = sha256_file(files_[i]);
      } catch (const std::exception&) {
        // unreadable bytes: the record is keyed by the path alone
      }
    }
    auto rec = failed_record(path, sha, kind, msg, elapsed);
    if (opt_.report_dir) {
      try {
        report::write_failed_capture_report(
            {path, sha, "", elapsed, {}, {}}, msg,
            *opt_.report_dir / report::capture_report_folder(path, rec.key));
      } catch (const std::exception& e) {
        sink_.issue({path, "report", e.what()});
      }
    }
    sink_.put(rec, ReplayIssue{path, kind, msg});
  }

  void apply(const Outcome& o) {
    if (o.cancelled) return;
    if (o.skipped) {
      sink_.skipped(o.key);
      return;
    }
    if (o.report_issue) sink_.issue({o.report_issue->path, o.report_issue->kind, o.report_issue->message});
    std::optional<ReplayIssue> issue;
    if (o.issue) issue = ReplayIssue{o.issue->path, o.issue->kind, o.issue->message};
    sink_.put(o.record, issue);
  }

  const std::vector<fs::path>& files_;
  const ReplayOptions& opt_;
  Sink& sink_;
  const std::atomic<bool>& cancel_;
};

}  // namespace

ReplaySummary run_replay(const ReplayOptions& opt, const ReplayCallbacks& cb,
                         const std::atomic<bool>& cancel) {
  if (opt.jobs < 1 || opt.jobs > 256) throw std::invalid_argument("--jobs must be in 1..256");
  if (opt.inputs.empty())
    throw std::invalid_argument("replay: no input given (files or folders of captures)");
  if (opt.out.empty()) throw std::invalid_argument("replay: --out RESULTS.h5 is required");
  const auto t0 = Clock::now();
  ReplaySummary sum;
  const auto found = find_captures(opt.inputs, {opt.out, acq::partial_path_for(opt.out)});
  sum.found = found.size();
  if (found.empty())
    throw std::invalid_argument("replay: no capture (*.h5, *.hdf5) found under the given paths");
  // A capture's held-out partner is part of that tube's record, not a tube.
  const auto all = without_heldout_partners(found, effective_holdout_patterns(opt.holdout), &sum.heldout_partners);
  const auto mine = select_shard(all, opt.shard);
  if (opt.report_dir) {
    std::error_code ec;
    fs::create_directories(*opt.report_dir, ec);
    if (ec)
      throw std::invalid_argument("--report: cannot create " + opt.report_dir->string() + ": " +
                                  ec.message());
  }
  Sink sink(opt, cb, mine.size());
  if (cb.progress) cb.progress(sink.counts());

  std::exception_ptr fatal;
  try {
    ReplayWork(mine, opt, sink, cancel).run();
  } catch (...) {  // the results file could not be written, or no worker could be started
    fatal = std::current_exception();
  }
  if (fatal) {
    try {
      sink.close();
    } catch (...) {
      // The first failure is the one to report.
    }
    std::rethrow_exception(fatal);
  }
  sink.close();

  sum.counts = sink.counts();
  sum.issues = sink.issues();
  for (const auto& i : sum.issues) sum.report_errors += i.kind == "report";
  sum.interrupted = cancel && sum.counts.done < sum.counts.total;
  sum.wall_s = seconds_since(t0);
  if (opt.report_dir) write_batch_summary(opt.out, *opt.report_dir);
  if (opt.limits) {
    sum.lot = summarize_lot_file(opt.out, *opt.limits);
    if (opt.report_dir) report::write_lot_report(*opt.limits, *sum.lot, opt.out.string(), *opt.report_dir);
  }
  if (opt.report_dir) write_index(opt.out, *opt.report_dir);
  return sum;
}

report::LotSummary summarize_lot_file(const fs::path& results, const report::Limits& limits) {
  std::vector<report::LotRecord> records;
  acq::for_each_result(results, [&](const acq::ResultRecord& r) {
    records.push_back({r.input_path, r.key, record_json(r)});
  });
  return report::summarize_lot(limits, std::move(records));
}

void write_index(const fs::path& results, const fs::path& report_dir) {
  std::vector<std::pair<std::string, nlohmann::json>> records;
  acq::for_each_result(results, [&](const acq::ResultRecord& r) { records.emplace_back(r.key, record_json(r)); });
  std::sort(records.begin(), records.end(), [](const auto& a, const auto& b) {
    return a.second.value("path", std::string()) < b.second.value("path", std::string());
  });
  report::write_index_html(records, results.string(), report_dir);
}

void write_batch_summary(const fs::path& results, const fs::path& report_dir) {
  std::vector<report::BatchEntry> entries;
  acq::for_each_result(results, [&](const acq::ResultRecord& r) {
    entries.push_back(report::batch_entry(r.key, record_json(r)));
  });
  report::write_batch_report(report::summarize(std::move(entries)), results.string(), report_dir);
}

}  // namespace piezo::jobs::replay
