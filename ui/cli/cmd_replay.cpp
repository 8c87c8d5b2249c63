// `piezobench replay PATH... --out RESULTS.h5`: headless replay of recorded
// captures (jobs/replay/replay_batch.hpp) with a progress bar and ETA, and
// `piezobench replay-merge A.h5 B.h5 ... --out ALL.h5` for sharded runs.
// Exit codes: 0 every capture replayed; 2 some captures were refused or
// failed (each reported, the batch went on) or bad options; 1 the batch
// itself failed or was interrupted (rerun the same command to resume). With
// --limits, captures that fail their limits do not change the exit code: the
// verdicts are data (the records, the lot summary), not errors of the run.
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cstdio>
#include <iostream>
#include <thread>

#include "acquisition/results_file.hpp"
#include "jobs/text/user_message.hpp"
#include "ui/cli/cli_common.hpp"
#include "jobs/replay/merge.hpp"
#include "jobs/replay/replay_batch.hpp"
#include "jobs/report/limits.hpp"
#include "jobs/report/lot_summary.hpp"
#include "ui/version.hpp"

namespace piezo::cli {

namespace {

std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop = true; }

std::string duration(double s) {
  if (s < 0) return "--:--";
  const long t = static_cast<long>(s + 0.5);
  char b[32];
  if (t >= 3600)
    std::snprintf(b, sizeof b, "%ld:%02ld:%02ld", t / 3600, (t / 60) % 60, t % 60);
  else
    std::snprintf(b, sizeof b, "%ld:%02ld", t / 60, t % 60);
  return b;
}

std::string progress_text(const jobs::replay::ReplayProgress& p) {
  char b[160];
  std::snprintf(b, sizeof b, "%zu/%zu ok %zu failed %zu done-before %zu | %.2f/s | ETA %s", p.done,
                p.total, p.ok, p.failed, p.skipped, p.rate_per_s, duration(p.eta_s).c_str());
  return b;
}

// Results files given by the user are input: a wrong one is exit 2, not an internal error.
template <class F>
auto as_input(F&& f) {
  try {
    return f();
  } catch (const acq::ResultsError& e) {
    throw InputError(e.what());
  }
}

// The lot against the limits: counts, then each capture that did not pass with its reasons.
void print_lot(const jobs::report::Limits& l, const jobs::report::LotSummary& s,
               const std::optional<std::filesystem::path>& report_dir) {
  std::printf("limits %s: %zu pass, %zu fail, %zu error of %zu record(s) in the results file%s\n",
              l.source.c_str(), s.pass, s.fail, s.error, s.captures.size(),
              report_dir ? (", lot report: " + (*report_dir / "lot.md").string()).c_str() : "");
  for (const auto& q : s.quantities) {
    const auto& lim = l.limits[q.limit];
    if (!lim.numeric()) continue;
    std::printf("  %-36s n %zu  mean %.6g  sd %.3g  fail low %zu high %zu  not measured %zu", lim.label.c_str(),
                q.n, q.mean, q.sd, q.below, q.above, q.not_measured);
    if (q.capability.cpk) std::printf("  Cpk %.2f", *q.capability.cpk);
    std::printf("\n");
  }
  for (const auto& c : s.captures)
    if (c.verdict.status != "pass") {
      std::printf("  %s %s:", c.verdict.status == "fail" ? "FAIL " : "ERROR", c.path.c_str());
      for (std::size_t k = 0; k < c.verdict.reasons.size(); ++k)
        std::printf("%s %s", k ? ";" : "", c.verdict.reasons[k].c_str());
      std::printf("\n");
    }
}

}  // namespace

std::size_t default_jobs() {
  const unsigned cores = std::thread::hardware_concurrency();  // 0: unknown
  return std::clamp<std::size_t>(cores, 1, 256);                 // run_replay's range
}

void register_replay_command(CLI::App& app, Context& ctx) {
  // ------------------------------------------------------------------ replay
  auto* r = app.add_subcommand("replay",
                               "Replay recorded captures headless: impedance, update, diagnosis");
  struct Args {
    std::vector<std::string> inputs;
    std::string out, shard = "0/1", report, jsonl, material, limits;
    std::size_t jobs = default_jobs();
    double timeout_s = 600.0;
    bool transverse = false;
    bool seed_chain = false;
    std::string holdout;
    update::OeOptions oe;
  };
  auto a = std::make_shared<Args>();
  r->add_option("PATH", a->inputs, "Capture files and folders (searched recursively for *.h5)")
      ->required();
  r->add_option("--out", a->out, "Results file (HDF5, piezo-replay/1); an existing one is resumed")
      ->required();
  r->add_option("--jobs", a->jobs,
                "Captures replayed in parallel (worker processes: a crash costs one capture); "
                "default: the number of cores")
      ->capture_default_str();
  r->add_option("--timeout", a->timeout_s,
                "Seconds one capture may take before its worker is killed and the capture "
                "recorded as hung")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 1e6));
  r->add_option("--shard", a->shard,
                "Replay shard I of N (0-based), e.g. $SLURM_ARRAY_TASK_ID/$SLURM_ARRAY_TASK_COUNT")
      ->capture_default_str();
  r->add_option("--report", a->report,
                "Folder for per-capture reports, exports and the batch summary");
  r->add_option("--jsonl", a->jsonl, "One JSON line per capture of this run");
  r->add_option("--material", a->material,
                "Nominal material (default: the capture's /setup/material, else apc850)");
  r->add_flag("--transverse", a->transverse,
              "Transversely isotropic class instead of the isotropic one");
  r->add_flag("--seed-chain", a->seed_chain,
              "Also run the seed's chain (Prony features -> extended CMCM, LM where it fails) beside the "
              "output-error fit; its constants go into parameters[].cmcm");
  r->add_option("--holdout,--holdout-pattern", a->holdout,
                "Held-out capture beside each capture, by name: {stem} is the capture's name without .h5 "
                "(e.g. holdout.h5); the diagnosis predicts it from its v1, and it is not replayed as a tube "
                "of its own. Default: {stem}-heldout.h5 (piezobench's own pairs), {stem}-holdout.h5, "
                "holdout.h5 or heldout.h5 beside the capture");
  r->add_option("--limits", a->limits,
                "Acceptance limits (TOML, see README 'Limits and the lot report'): pass/fail per "
                "capture with the reasons, and the lot summary (counts, distributions, outliers, Cpk)");
  add_chain_tolerance_options(r, a->oe);
  add_json_flag(r, ctx);
  r->callback([&ctx, a] {
    ctx.exit_code = run_command(ctx, [&] {
      jobs::replay::ReplayOptions opt;
      opt.inputs = a->inputs;
      opt.out = a->out;
      opt.jobs = a->jobs;
      opt.capture_timeout_s = a->timeout_s;
      opt.shard = jobs::replay::parse_shard(a->shard);
      if (!a->report.empty()) opt.report_dir = a->report;
      if (!a->jsonl.empty()) opt.jsonl = a->jsonl;
      opt.material = a->material;
      opt.oe_options = a->oe;
      opt.isotropic = !a->transverse;
      opt.seed_chain = a->seed_chain;
      opt.holdout = a->holdout;
      opt.software = std::string("piezobench ") + kVersion + " replay";
      if (!a->limits.empty()) {  // a malformed file stops the run before any capture
        try {
          opt.limits = jobs::report::read_limits(a->limits);
        } catch (const jobs::report::LimitsError& e) {
          throw InputError(std::string("--limits: ") + e.what());
        }
      }
      g_stop = false;
      std::signal(SIGINT, on_signal);
      std::signal(SIGTERM, on_signal);  // Slurm's warning before a time-limit kill
      const bool tty = ::isatty(STDERR_FILENO);
      ProgressBar bar("replay");
      std::size_t last_decile = 0;
      jobs::replay::ReplayCallbacks cb;
      cb.progress = [&](const jobs::replay::ReplayProgress& p) {
        if (tty) {
          bar.update(p.total ? static_cast<double>(p.done) / p.total : 1.0, progress_text(p));
        } else if (p.total &&
                   p.done * 10 / p.total > last_decile) {  // logs (Slurm, parallel): every 10 %
          last_decile = p.done * 10 / p.total;
          std::fprintf(stderr, "replay: %s\n", progress_text(p).c_str());
        }
      };
      cb.issue = [&](const jobs::replay::ReplayIssue& i) {
        if (tty) std::fprintf(stderr, "\n");
        const char* what = i.kind == "report" ? "report not written" : "skipped";
        const std::string message = jobs::user_message(i.message);  // without internal function names
        if (message.rfind(i.path, 0) == 0)  // the message names the file already
          std::fprintf(stderr, "piezobench: replay: %s: %s\n", what, message.c_str());
        else
          std::fprintf(stderr, "piezobench: replay: %s: %s: %s\n", what, i.path.c_str(), message.c_str());
      };
      auto s = as_input([&] { return jobs::replay::run_replay(opt, cb, g_stop); });
      bar.finish();
      std::signal(SIGINT, SIG_DFL);
      std::signal(SIGTERM, SIG_DFL);
      const auto& c = s.counts;
      nlohmann::json j = {{"results", opt.out.string()},
                          {"found", s.found},
                          {"heldout_partners", s.heldout_partners},
                          {"shard", a->shard},
                          {"total", c.total},
                          {"replayed", c.ok},
                          {"failed", c.failed},
                          {"done_before", c.skipped},
                          {"failed_before", c.failed_before},
                          {"wall_s", s.wall_s},
                          {"captures_per_s", c.ok + c.failed ? (c.ok + c.failed) / s.wall_s : 0.0},
                          {"jobs", opt.jobs},
                          {"interrupted", s.interrupted}};
      j["issues"] = nlohmann::json::array();
      for (const auto& i : s.issues)
        j["issues"].push_back({{"path", i.path}, {"kind", i.kind}, {"message", i.message}});
      if (s.lot) j["lot"] = jobs::report::lot_json(*opt.limits, *s.lot);
      if (ctx.json) {
        print_json(j);
      } else {
        std::printf("replay: %zu capture(s) found, %zu in shard %s\n", s.found, c.total,
                    a->shard.c_str());
        if (s.heldout_partners)
          std::printf("replay: %zu of them held-out partners of another capture (used by its diagnosis, "
                      "not counted as tubes)\n",
                      s.heldout_partners);
        std::printf(
            "replay: %zu replayed, %zu failed, %zu done before%s; %.1f s, %.2f captures/s "
            "with --jobs %zu\n",
            c.ok, c.failed, c.skipped,
            c.failed_before
                ? (" (" + std::to_string(c.failed_before) + " of them crashed or hung a worker)").c_str()
                : "",
            s.wall_s, j["captures_per_s"].get<double>(), opt.jobs);
        std::printf("results: %s%s%s\n", opt.out.string().c_str(),
                    opt.report_dir ? ", report: " : "",
                    opt.report_dir ? (*opt.report_dir / "summary.md").string().c_str() : "");
        if (s.lot) print_lot(*opt.limits, *s.lot, opt.report_dir);
        if (s.interrupted) std::printf("interrupted: run the same command again to resume\n");
      }
      if (s.interrupted || s.report_errors)
        ctx.exit_code = kInternal;
      else if (c.failed || c.failed_before)
        ctx.exit_code = kBadInput;
    });
  });
}

void register_replay_merge_command(CLI::App& app, Context& ctx) {
  auto* m = app.add_subcommand("replay-merge", "Merge the results files of sharded replays");
  struct MergeArgs {
    std::vector<std::string> inputs;
    std::string out, report, jsonl;
    bool overwrite = false;
  };
  auto ma = std::make_shared<MergeArgs>();
  m->add_option("RESULTS", ma->inputs, "Results files of the shards")->required();
  m->add_option("--out", ma->out, "Merged results file")->required();
  m->add_flag("--overwrite", ma->overwrite, "Replace an existing merged file");
  m->add_option("--report", ma->report, "Folder for the batch summary of the merged results");
  m->add_option("--jsonl", ma->jsonl, "One JSON line per merged record");
  add_json_flag(m, ctx);
  m->callback([&ctx, ma] {
    ctx.exit_code = run_command(ctx, [&] {
      jobs::replay::MergeOptions opt;
      for (const auto& i : ma->inputs) opt.inputs.emplace_back(i);
      opt.out = ma->out;
      opt.overwrite = ma->overwrite;
      opt.software = std::string("piezobench ") + kVersion + " replay-merge";
      if (!ma->report.empty()) opt.report_dir = ma->report;
      if (!ma->jsonl.empty()) opt.jsonl = ma->jsonl;
      auto s = as_input([&] { return jobs::replay::merge_results(opt); });
      for (const auto& w : s.warnings)
        std::cerr << "piezobench: replay-merge: warning: " << w << "\n";
      if (ctx.json) {
        print_json({{"results", opt.out.string()},
                    {"inputs", ma->inputs},
                    {"records", s.records},
                    {"ok", s.ok},
                    {"failed", s.failed},
                    {"duplicates", s.duplicates},
                    {"warnings", s.warnings}});
      } else {
        std::printf(
            "replay-merge: %zu record(s) (%zu ok, %zu failed) from %zu file(s) into %s; %zu "
            "duplicate(s) left out\n",
            s.records, s.ok, s.failed, opt.inputs.size(), opt.out.string().c_str(), s.duplicates);
      }
    });
  });
}

}  // namespace piezo::cli
