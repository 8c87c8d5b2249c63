#include "ui/replay/replay_batch.hpp"

#include <chrono>
#include <fstream>
#include <map>
#include <mutex>
#include <stdexcept>
#include <thread>

#include "acquisition/capture_file.hpp"
#include "acquisition/results_file.hpp"
#include "ui/pipeline.hpp"
#include "ui/replay/replay_record.hpp"
#include "ui/replay/sha256.hpp"
#include "ui/report/batch_summary.hpp"
#include "ui/report/capture_report.hpp"

namespace piezo::replay {

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

// Everything the workers share: the results file, the JSON lines, counters.
class Sink {
 public:
  Sink(const ReplayOptions& opt, const ReplayCallbacks& cb, std::size_t total)
      : results_(acq::ResultsFile::open_or_create(opt.out, opt.software)), cb_(cb) {
    counts_.total = total;
    for (auto& e : results_.index()) {
      if (e.status == "ok") done_.emplace(e.key, e.input_path);
      by_path_[e.input_path].push_back(e.key);
    }
    if (opt.jsonl) {
      jsonl_.open(*opt.jsonl, std::ios::trunc);
      if (!jsonl_) throw std::invalid_argument("--jsonl: cannot write " + opt.jsonl->string());
    }
  }

  // done_ is only read after construction: no lock needed.
  bool finished(const std::string& key) const { return done_.count(key) > 0; }

  // A capture finished earlier: its stored line goes to this run's JSON lines.
  void skipped(const std::string& key) {
    std::lock_guard lock(mu_);
    if (jsonl_.is_open())
      if (auto rec = results_.get(key)) line(*rec);
    ++counts_.skipped;
    step();
  }

  void put(const acq::ResultRecord& rec, const std::optional<ReplayIssue>& issue) {
    std::lock_guard lock(mu_);
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

  void report_issue(const ReplayIssue& i) {  // caller holds mu_ or is single-threaded
    issues_.push_back(i);
    if (cb_.issue) cb_.issue(i);
  }
  void issue(const ReplayIssue& i) {
    std::lock_guard lock(mu_);
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
    jsonl_ << record_json(rec).dump() << "\n";
    jsonl_.flush();
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
  std::mutex mu_;
  std::ofstream jsonl_;
  std::map<std::string, std::string> done_;  // key → path of finished ("ok") records
  std::map<std::string, std::vector<std::string>> by_path_;  // path → keys
  ReplayProgress counts_;
  std::size_t processed_ = 0;
  std::vector<ReplayIssue> issues_;
  Clock::time_point t0_ = Clock::now();
};

struct Worker {
  const ReplayOptions& opt;
  Sink& sink;
  const std::atomic<bool>& cancel;

  void replay(const fs::path& file) {
    const std::string path = file.string();
    const auto t0 = Clock::now();
    std::string sha;
    try {
      sha = sha256_file(file);
    } catch (const std::exception& e) {
      fail(path, "", "bad capture", naming(path, e.what()), t0);
      return;
    }
    const std::string key = record_key(path, sha);
    if (sink.finished(key)) {
      sink.skipped(key);
      return;
    }
    std::string material = opt.material;
    ui::PipelineResult result;
    try {
      if (material.empty()) {
        acq::ReadOptions ro;
        ro.load_samples = false;  // attributes only: which nominal model to update
        material = acq::read_capture(file, ro).setup.material.value_or("apc850");
      }
      ui::PipelineRequest req;
      req.replay_capture = path;
      req.material = material;
      req.isotropic = opt.isotropic;
      result = ui::run_pipeline(req, nullptr, cancel);
    } catch (const acq::CaptureError& e) {
      fail(path, sha, "bad capture", e.what(), t0);
      return;
    } catch (const std::invalid_argument& e) {
      fail(path, sha, "bad input", naming(path, e.what()), t0);
      return;
    } catch (const std::exception& e) {
      fail(path, sha, "failed", naming(path, e.what()), t0);
      return;
    }
    if (cancel) return;  // a cancelled pipeline returns a partial result: not a finished capture
    const double elapsed = seconds_since(t0);
    std::optional<ReplayIssue> issue;
    if (opt.report_dir) {
      try {
        report::write_capture_report(result, {path, sha, material, elapsed},
                                     *opt.report_dir / report::capture_report_folder(path, key));
      } catch (const std::exception& e) {
        issue = ReplayIssue{path, "report", e.what()};
      }
    }
    sink.put(ok_record(path, sha, material, result, elapsed), issue);
  }

  void fail(const std::string& path, const std::string& sha, const std::string& kind,
            const std::string& msg, Clock::time_point t0) {
    const double elapsed = seconds_since(t0);
    std::optional<ReplayIssue> issue = ReplayIssue{path, kind, msg};
    auto rec = failed_record(path, sha, kind, msg, elapsed);
    if (opt.report_dir) {
      try {
        report::write_failed_capture_report(
            {path, sha, "", elapsed}, msg,
            *opt.report_dir / report::capture_report_folder(path, rec.key));
      } catch (const std::exception& e) {
        sink.issue({path, "report", e.what()});
      }
    }
    sink.put(rec, issue);
  }
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
  const auto all = find_captures(opt.inputs, {opt.out, acq::partial_path_for(opt.out)});
  sum.found = all.size();
  if (all.empty())
    throw std::invalid_argument("replay: no capture (*.h5, *.hdf5) found under the given paths");
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

  std::atomic<std::size_t> next{0};
  std::mutex fatal_mu;
  std::exception_ptr fatal;
  std::atomic<bool> stop{false};
  auto work = [&] {
    Worker w{opt, sink, cancel};
    while (!cancel && !stop) {
      const std::size_t i = next++;
      if (i >= mine.size()) return;
      try {
        w.replay(mine[i]);
      } catch (...) {  // the results file could not be written: stop the batch
        std::lock_guard lock(fatal_mu);
        if (!fatal) fatal = std::current_exception();
        stop = true;
      }
    }
  };
  const std::size_t n_threads = std::min(opt.jobs, std::max<std::size_t>(1, mine.size()));
  std::vector<std::thread> threads;
  try {
    for (std::size_t k = 1; k < n_threads; ++k) threads.emplace_back(work);
  } catch (...) {  // no thread to be had: stop those started, never leave one joinable
    stop = true;
    for (auto& t : threads) t.join();
    throw;
  }
  work();
  for (auto& t : threads) t.join();
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
  return sum;
}

void write_batch_summary(const fs::path& results, const fs::path& report_dir) {
  std::vector<report::BatchEntry> entries;
  acq::for_each_result(results, [&](const acq::ResultRecord& r) {
    entries.push_back(report::batch_entry(r.key, record_json(r)));
  });
  report::write_batch_report(report::summarize(std::move(entries)), results.string(), report_dir);
}

}  // namespace piezo::replay
