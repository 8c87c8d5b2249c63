// `piezobench replay` and `replay-merge` end to end on small batches of
// simulated captures: a corrupted capture is reported and skipped, reports
// and exports are written, a killed run resumes without redoing finished
// captures, and four merged shards equal one unsharded run.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>

#include <chrono>
#include <fstream>
#include <set>
#include <thread>

#include "tests/replay/replay_test_support.hpp"

extern char** environ;
using namespace piezo;
namespace fs = std::filesystem;

namespace {

// Four good captures in nested folders (two production lines) and a truncated one.
fs::path make_batch(const fs::path& dir, int good = 4, bool corrupt = true) {
  const fs::path in = dir / "captures";
  const double ye[] = {6.66e10, 6.70e10, 6.62e10, 6.68e10, 6.64e10, 6.69e10};
  for (int k = 0; k < good; ++k)
    test::make_capture(in / (k % 2 ? "line2/sub" : "line1") / ("T-00" + std::to_string(k) + ".h5"),
                       ye[k % 6], 10 + k);
  if (corrupt) test::make_truncated_capture(in / "line1" / "T-bad.h5");
  std::ofstream(in / "line1" / "notes.txt") << "not a capture, not picked up from a folder";
  return in;
}


std::string sha256sum(const fs::path& f) {  // an independent digest: coreutils
  auto r = ::popen(("sha256sum '" + f.string() + "'").c_str(), "r");
  char buf[128] = {};
  std::string out = std::fgets(buf, sizeof buf, r) ? std::string(buf).substr(0, 64) : "";
  ::pclose(r);
  return out;
}

std::size_t lines_in(const fs::path& f) {
  std::ifstream in(f);
  std::size_t n = 0;
  for (std::string line; std::getline(in, line);) ++n;
  return n;
}

}  // namespace

TEST(CliReplay, BatchReportsAndSkipsACorruptedCaptureWritesReportsAndResumes) {
  const auto dir = test::fresh_dir("replay-batch");
  const auto in = make_batch(dir);
  const auto out = dir / "results.h5", jsonl = dir / "results.jsonl", rep = dir / "report";
  const std::string cmd = "replay '" + in.string() + "' --jobs 2 --out '" + out.string() +
                          "' --jsonl '" + jsonl.string() + "' --report '" + rep.string() +
                          "' --json";
  auto r = test::run_cli(cmd);
  // Exit 2: the batch completed, one capture was refused.
  ASSERT_EQ(r.exit_code, 2) << r.err;
  auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["found"], 5);
  EXPECT_EQ(j["replayed"], 4);
  EXPECT_EQ(j["failed"], 1);
  EXPECT_EQ(j["done_before"], 0);
  EXPECT_GT(j["captures_per_s"].get<double>(), 0.0);
  const std::string bad = (in / "line1" / "T-bad.h5").string();
  ASSERT_EQ(j["issues"].size(), 1u);
  EXPECT_EQ(j["issues"][0]["path"], bad);
  EXPECT_EQ(j["issues"][0]["kind"], "bad capture");
  EXPECT_NE(r.err.find("skipped: " + bad + ": /"), std::string::npos) << r.err;

  // One JSON line per capture, with its path and SHA-256.
  auto lines = test::read_lines(jsonl);
  ASSERT_EQ(lines.size(), 5u);
  std::set<std::string> paths;
  for (const auto& l : lines) {
    paths.insert(l["path"].get<std::string>());
    EXPECT_EQ(l["sha256"], sha256sum(l["path"].get<std::string>())) << l["path"];
    if (l["path"] == bad) {
      EXPECT_EQ(l["status"], "failed");
      continue;
    }
    EXPECT_EQ(l["status"], "ok");
    ASSERT_EQ(l["result"]["parameters"].size(), 4u) << l.dump();
    EXPECT_EQ(l["result"]["parameters"][0]["name"], "YE11");
    EXPECT_EQ(l["material"], "apc850");  // from the capture's /setup/material
  }
  EXPECT_EQ(paths.size(), 5u);

  // The results file holds the same records, with the curves.
  auto content = test::read_content(out);
  ASSERT_EQ(content.size(), 5u);
  for (const auto& [key, c] : content) {
    if (c.path == bad) {
      EXPECT_TRUE(c.curves.empty());
      continue;
    }
    ASSERT_EQ(c.curves.size(), 5u) << c.path;  // Prony, FFT, cross-spectra, original, updated model
    EXPECT_EQ(c.curves.front().label, "measured (Prony-SS)");
    EXPECT_EQ(c.curves.back().label, "updated model");
    EXPECT_GT(c.curves.front().f_hz.size(), 100u);
  }

  // Reports: per capture a folder with plot, summary and exports; the batch summary.
  std::size_t folders = 0;
  for (const auto& e : fs::directory_iterator(rep / "captures")) {
    ++folders;
    EXPECT_TRUE(fs::exists(e.path() / "summary.md")) << e.path();
    if (e.path().filename().string().find("T-bad") != std::string::npos) continue;  // line1-T-bad-…
    for (const char* f : {"impedance.svg", "impedance.csv", "impedance.s1p", "result.json"})
      EXPECT_GT(fs::file_size(e.path() / f), 100u) << e.path() / f;
    // The per-mode figures (issue 19): the table, and the admittance plane it links.
    std::ifstream cmd_md(e.path() / "summary.md");
    std::stringstream cs;
    cs << cmd_md.rdbuf();
    EXPECT_NE(cs.str().find("| mode | fs [kHz] | fp [kHz] | k_eff | Qm (branch) |"), std::string::npos) << cs.str();
    if (cs.str().find("(nyquist.svg)") != std::string::npos) {
      EXPECT_GT(fs::file_size(e.path() / "nyquist.svg"), 1000u) << e.path();
    }
  }
  EXPECT_EQ(folders, 5u);
  std::ifstream md(rep / "summary.md");
  std::stringstream ss;
  ss << md.rdbuf();
  EXPECT_NE(ss.str().find("5 (4 replayed, 1 failed)"), std::string::npos) << ss.str();
  EXPECT_NE(ss.str().find("| YE11 | Pa | 4 |"), std::string::npos) << ss.str();
  EXPECT_TRUE(fs::exists(rep / "distributions.svg"));
  // One self-contained page (issue 41 item 3): a row per capture linking its
  // folder, the batch plot inline, and no limits loaded said as such.
  std::ifstream html_in(rep / "index.html");
  std::stringstream hs;
  hs << html_in.rdbuf();
  const std::string html = hs.str();
  EXPECT_NE(html.find("<svg"), std::string::npos);
  EXPECT_NE(html.find("No limits loaded"), std::string::npos);
  EXPECT_NE(html.find("/summary.md\">" + bad + "</a>"), std::string::npos) << html.substr(0, 2000);
  EXPECT_NE(html.find("failed: "), std::string::npos);
  std::size_t rows = 0;
  for (auto p = html.find("<tr><td>"); p != std::string::npos; p = html.find("<tr><td>", p + 1)) ++rows;
  EXPECT_EQ(rows, 5u);

  // Run again: the finished captures are recognised by path + SHA-256 and
  // skipped, the refused one is tried (and refused) again.
  auto again = test::run_cli(cmd);
  ASSERT_EQ(again.exit_code, 2) << again.err;
  auto j2 = nlohmann::json::parse(again.out);
  EXPECT_EQ(j2["replayed"], 0);
  EXPECT_EQ(j2["done_before"], 4);
  EXPECT_EQ(j2["failed"], 1);
  EXPECT_EQ(test::read_lines(jsonl).size(),
            5u);  // this run's lines: the stored ones for skipped captures
  test::expect_same_content(content, test::read_content(out));
  fs::remove_all(dir);
}

TEST(CliReplay, FourMergedShardsEqualOneUnshardedRun) {
  const auto dir = test::fresh_dir("replay-shards");
  const auto in = make_batch(dir, 5, true);
  const auto all = dir / "all.h5";
  auto r =
      test::run_cli("replay '" + in.string() + "' --jobs 2 --out '" + all.string() + "' --json");
  ASSERT_EQ(r.exit_code, 2) << r.err;
  // The shards list the inputs in another order (the partition sorts paths).
  std::string shards;
  std::set<std::string> seen;
  for (int i = 0; i < 4; ++i) {
    const auto s = dir / ("shard" + std::to_string(i) + ".h5");
    auto rs =
        test::run_cli("replay '" + (in / "line2").string() + "' '" + (in / "line1").string() +
                      "' --shard " + std::to_string(i) + "/4 --out '" + s.string() + "' --json");
    ASSERT_TRUE(rs.exit_code == 0 || rs.exit_code == 2) << rs.err;
    auto js = nlohmann::json::parse(rs.out);
    EXPECT_EQ(js["found"], 6);
    EXPECT_EQ(js["total"], i < 2 ? 2 : 1);  // 6 captures: 2, 2, 1, 1
    for (const auto& [key, c] : test::read_content(s))
      EXPECT_TRUE(seen.insert(key).second) << c.path << " twice";
    shards += " '" + s.string() + "'";
  }
  EXPECT_EQ(seen.size(), 6u);
  const auto merged = dir / "merged.h5";
  auto m = test::run_cli("replay-merge" + shards + " --out '" + merged.string() + "' --json");
  ASSERT_EQ(m.exit_code, 0) << m.err;
  auto jm = nlohmann::json::parse(m.out);
  EXPECT_EQ(jm["records"], 6);
  EXPECT_EQ(jm["failed"], 1);
  test::expect_same_content(test::read_content(all), test::read_content(merged));
  // Merging again into an existing file needs --overwrite; a shard merged twice counts as
  // duplicates.
  EXPECT_EQ(test::run_cli("replay-merge" + shards + " --out '" + merged.string() + "'").exit_code,
            2);
  auto m2 = test::run_cli("replay-merge" + shards + " '" + (dir / "shard0.h5").string() +
                          "' --overwrite --out '" + merged.string() + "' --json");
  ASSERT_EQ(m2.exit_code, 0) << m2.err;
  EXPECT_EQ(nlohmann::json::parse(m2.out)["duplicates"], 2);
  test::expect_same_content(test::read_content(all), test::read_content(merged));
  fs::remove_all(dir);
}

TEST(CliReplay, KilledRunResumesWithoutRedoingFinishedCaptures) {
  const auto dir = test::fresh_dir("replay-kill");
  const auto in = make_batch(dir, 6, false);
  const auto out = dir / "results.h5", jsonl = dir / "progress.jsonl";
  const std::string exe = PIEZO_CLI, in_s = in.string(), out_s = out.string(),
                    jsonl_s = jsonl.string();
  const char* argv[] = {exe.c_str(), "replay",      in_s.c_str(), "--jobs",        "1",
                        "--out",     out_s.c_str(), "--jsonl",    jsonl_s.c_str(), nullptr};
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&fa, 2, "/dev/null", O_WRONLY, 0);
  pid_t pid = 0;
  ASSERT_EQ(posix_spawn(&pid, exe.c_str(), &fa, nullptr, const_cast<char**>(argv), environ), 0);
  posix_spawn_file_actions_destroy(&fa);
  // SIGKILL (no chance to clean up) once two captures are finished: each JSON
  // line is written after its record is flushed to the results file.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (lines_in(jsonl) < 2 && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  ::kill(pid, SIGKILL);
  int status = 0;
  ::waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status)) << "the replay finished before it could be killed";

  // The file is readable and holds the finished captures.
  auto before = test::read_content(out);
  ASSERT_GE(before.size(), 2u);
  ASSERT_LT(before.size(), 6u);
  std::map<std::string, std::pair<std::string, double>> stamps;  // key → (replayed_utc, elapsed_s)
  acq::for_each_result(out, [&](const acq::ResultRecord& rec) {
    stamps[rec.key] = {rec.replayed_utc, rec.elapsed_s};
  });

  auto r = test::run_cli("replay '" + in_s + "' --jobs 2 --out '" + out_s + "' --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["done_before"], before.size());
  EXPECT_EQ(j["replayed"], 6 - before.size());
  auto after = test::read_content(out);
  EXPECT_EQ(after.size(), 6u);
  // Records finished before the kill are untouched (not redone): same stamps, same content.
  acq::for_each_result(out, [&](const acq::ResultRecord& rec) {
    auto it = stamps.find(rec.key);
    if (it == stamps.end()) return;
    EXPECT_EQ(it->second.first, rec.replayed_utc);
    EXPECT_EQ(it->second.second, rec.elapsed_s);
  });
  for (const auto& [key, c] : before) {
    std::map<std::string, test::Content> one{{key, c}}, other{{key, after.at(key)}};
    test::expect_same_content(one, other);
  }
  fs::remove_all(dir);
}

TEST(CliReplay, BadOptionsAndFilesAreRefusedClearly) {
  const auto dir = test::fresh_dir("replay-bad");
  test::make_capture(dir / "T.h5", 6.66e10, 1);
  test::make_capture(dir / "U.h5", 6.66e10, 2);
  auto r = test::run_cli("replay '" + dir.string() + "' --shard 4/4 --out '" +
                         (dir / "r.h5").string() + "'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--shard '4/4'"), std::string::npos) << r.err;
  r = test::run_cli("replay '" + (dir / "missing").string() + "' --out '" +
                    (dir / "r.h5").string() + "'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find((dir / "missing").string() + ": no such file"), std::string::npos) << r.err;
  fs::create_directories(dir / "empty");
  r = test::run_cli("replay '" + (dir / "empty").string() + "' --out '" + (dir / "r.h5").string() +
                    "'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("no capture"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "r.h5"));
  // A capture given as the results file is refused, and left as it was.
  const auto before = fs::file_size(dir / "T.h5");
  r = test::run_cli("replay '" + dir.string() + "' --out '" + (dir / "T.h5").string() + "'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("expected \"piezo-replay\""), std::string::npos) << r.err;
  EXPECT_EQ(fs::file_size(dir / "T.h5"), before);
  // replay-merge of something that is not a results file: nothing is written.
  r = test::run_cli("replay-merge '" + (dir / "T.h5").string() + "' --out '" +
                    (dir / "m.h5").string() + "'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find((dir / "T.h5").string()), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "m.h5"));
  EXPECT_FALSE(fs::exists(dir / "m.h5.partial"));
  fs::remove_all(dir);
}

// Issue 18: `replay --holdout NAME` pairs each capture with the held-out
// capture beside it (the refsim corpus's folders: fit.h5 + holdout.h5); the
// one-shot diagnosis predicts it. An unreadable held-out file is a warning,
// not the capture's failure; a held-out partner is not a tube: it is not
// replayed on its own (issue 41 item 3).
TEST(CliReplay, HoldoutPairsEachCaptureWithTheFileBesideIt) {
  const fs::path corpus = fs::path(PIEZO_SOURCE_DIR) / ".." / "shared" / "corpus" / "refsim-v1";
  if (!fs::exists(corpus / "05" / "fit.h5")) GTEST_SKIP() << "no corpus at " << corpus;
  const auto dir = test::fresh_dir("replay-holdout");
  for (const char* c : {"05", "12"}) {
    fs::create_directories(dir / "in" / c);
    for (const char* f : {"fit.h5", "holdout.h5"}) fs::copy_file(corpus / c / f, dir / "in" / c / f);
  }
  const auto out = dir / "results.h5", jsonl = dir / "results.jsonl";
  auto r = test::run_cli("replay '" + (dir / "in").string() + "' --holdout holdout.h5 --jobs 2 --out '" +
                         out.string() + "' --jsonl '" + jsonl.string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  int paired = 0, alone = 0;
  for (const auto& j : test::read_lines(jsonl)) {
    ASSERT_EQ(j["status"], "ok") << j.dump().substr(0, 400);
    const auto& d = j["result"]["diagnosis"];
    const std::string path = j["path"];
    if (path.find("fit.h5") != std::string::npos) {
      ++paired;
      EXPECT_FALSE(d["gap_heldout"].is_null()) << path;
      EXPECT_NE(d["heldout_data"].get<std::string>().find("holdout.h5"), std::string::npos) << path;
      const std::string want = path.find("/05/") != std::string::npos ? "series_resistance" : "none";
      EXPECT_EQ(d["verdict"]["effect"], want) << path;
    } else {
      ++alone;
      EXPECT_TRUE(d["gap_heldout"].is_null()) << path;  // a held-out file has no partner of its own
    }
  }
  EXPECT_EQ(paired, 2);
  EXPECT_EQ(alone, 0);

  // {stem}: fit.h5 → fit-heldout.h5, here not a capture at all.
  const auto dir2 = dir / "junk";
  fs::create_directories(dir2);
  fs::copy_file(corpus / "12" / "fit.h5", dir2 / "fit.h5");
  std::ofstream(dir2 / "fit-heldout.h5") << "not HDF5";
  const auto jsonl2 = dir / "junk.jsonl";
  r = test::run_cli("replay '" + (dir2 / "fit.h5").string() + "' --holdout '{stem}-heldout.h5' --out '" +
                    (dir / "junk.h5").string() + "' --jsonl '" + jsonl2.string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto lines = test::read_lines(jsonl2);
  ASSERT_EQ(lines.size(), 1u);
  const auto& j = lines.front();
  EXPECT_EQ(j["status"], "ok");
  EXPECT_NE(j.dump().find("fit-heldout.h5 cannot be read"), std::string::npos) << j.dump().substr(0, 600);
  fs::remove_all(dir);
}
