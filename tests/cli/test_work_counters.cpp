// Issue 43 item 3: the work of a replayed capture and of a diagnosis,
// counted and bounded. FE modal solves, Prony-SS decompositions and FFTs are
// deterministic for a given capture on machines of our kind; the bounds are
// the counts measured when the counters went in (2026-11-28) plus 20 %, so a
// change that makes the pipeline do markedly more work fails here without any
// timing assertion, and one that makes it do less lowers the bounds by hand.
// The counts: replay of refsim-v1/12 130 modal solves, 1 decomposition, 1356
// FFTs; diagnose of refsim-v1/07 with its hold-out (a lack-of-fit case, the
// costliest of the corpus) 593, 1, 2857 (132 and 631 modal solves before the
// output-error fit kept every port model it built, 1390 and 2942 FFTs before
// it kept the spectrum of a zero record it filters again; 2026-11-28 afternoon).
// The diagnosis then 522, 1, 2381 (593 and 2857 before a scanned effect's
// coordinate got its own LM trust region, OeOptions::effect_max_step; 2026-11-28
// evening): the bounds below are those counts. refsim-v1/01 with its hold-out
// 704, 1, 2368 (921 and 2997 before that change: its bound, 845, catches the
// scan's crawl of 0.3 typical sizes an iteration, which 07's alone would not).
// The effect scan's runs on a surrogate of the port model (reduced bases,
// OeOptions::scan_surrogate; 2026-11-29) took 07 to 328 modal solves (and 231
// reduced port models) and 01 to 503 (257): the bounds below, which the
// scan on exact models (522 and 704) fails.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "tests/support/run_cli.hpp"

namespace {

namespace fs = std::filesystem;
const fs::path kCorpus = fs::path(PIEZO_SOURCE_DIR) / ".." / "shared" / "corpus" / "refsim-v1";

void expect_work(const nlohmann::json& w, long modal, long prony, long ffts) {
  ASSERT_TRUE(w.is_object()) << "no work counts in the report";
  const long m = w["modal_solves"], p = w["prony_decompositions"], f = w["ffts"];
  EXPECT_GT(m, 0) << "the counters count nothing";
  EXPECT_LE(m, modal + modal / 5) << "FE modal solves up more than 20 % (" << m << " for " << modal << ")";
  EXPECT_LE(p, prony) << "Prony decompositions up (" << p << " for " << prony << ")";
  EXPECT_LE(f, ffts + ffts / 5) << "FFTs up more than 20 % (" << f << " for " << ffts << ")";
  // The phases add up to the totals.
  long sm = 0, sp = 0, sf = 0;
  for (const auto& ph : w["phases"]) {
    sm += ph["modal_solves"].get<long>();
    sp += ph["prony_decompositions"].get<long>();
    sf += ph["ffts"].get<long>();
  }
  EXPECT_EQ(sm, m);
  EXPECT_EQ(sp, p);
  EXPECT_EQ(sf, f);
}

TEST(WorkCounters, ReplayOfOneCorpusCapture) {
  if (!fs::exists(kCorpus / "12" / "fit.h5")) GTEST_SKIP() << "no corpus at " << kCorpus;
  const fs::path dir = fs::temp_directory_path() / ("piezo-work-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const auto r = piezo::test::run_cli("replay " + (kCorpus / "12" / "fit.h5").string() + " --out " +
                                      (dir / "r.h5").string() + " --jsonl " + (dir / "r.jsonl").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream in(dir / "r.jsonl");
  std::string line;
  ASSERT_TRUE(std::getline(in, line));
  const auto j = nlohmann::json::parse(line);
  expect_work(j["result"]["work"], 130, 1, 1356);
  // The seed's chain is off in a replay and the output-error fit converged: no
  // FE work in its phase.
  for (const auto& ph : j["result"]["work"]["phases"]) {
    if (ph["phase"].get<std::string>().find("CMCM") != std::string::npos) {
      EXPECT_EQ(ph["modal_solves"], 0) << ph;
    }
  }
  fs::remove_all(dir);
}

// `diagnose` of a corpus capture with its hold-out, its work against the counts.
void expect_diagnosis_work(const std::string& capture, long modal, long prony, long ffts) {
  const auto r = piezo::test::run_cli("diagnose " + (kCorpus / capture / "fit.h5").string() + " --holdout " +
                                      (kCorpus / capture / "holdout.h5").string() + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto w = nlohmann::json::parse(r.out)["work"];
  expect_work(w, modal, prony, ffts);
  // Its effect scan ran on the surrogate.
  EXPECT_GT(w.value("reduced_port_models", 0L), 0) << w;
}

TEST(WorkCounters, DiagnosisWithItsHoldout) {
  if (!fs::exists(kCorpus / "07" / "fit.h5")) GTEST_SKIP() << "no corpus at " << kCorpus;
  expect_diagnosis_work("07", 328, 1, 2381);
}

TEST(WorkCounters, DiagnosisWhoseEffectsLieManyTypicalSizesAway) {
  // refsim 01: the scanned DAQ input resistance, dielectric loss and channel
  // skew end 6–9 typical sizes from none.
  if (!fs::exists(kCorpus / "01" / "fit.h5")) GTEST_SKIP() << "no corpus at " << kCorpus;
  expect_diagnosis_work("01", 503, 1, 2368);
}

// The counts are the capture's, not the scheduling's: a fit on two threads
// (`--jobs 1`) and on one (`--jobs 2`: the single worker's fit) count the same
// work, phase by phase. (Before the spectrum of a zero record was kept once
// for every problem sharing the columns, refsim 19 counted one FFT more on two
// threads: two held-out predictions running at once each made their own.)
TEST(WorkCounters, TheCountsDoNotDependOnTheThreads) {
  if (!fs::exists(kCorpus / "19" / "fit.h5")) GTEST_SKIP() << "no corpus at " << kCorpus;
  const fs::path dir = fs::temp_directory_path() / ("piezo-work-threads-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  nlohmann::json work[2];
  for (int jobs : {1, 2}) {
    const std::string n = jobs == 1 ? "1" : "2";
    const fs::path jsonl = dir / (jobs == 1 ? "r1.jsonl" : "r2.jsonl");
    const auto r = piezo::test::run_cli("replay " + (kCorpus / "19" / "fit.h5").string() + " --jobs " + n +
                                        " --out " + (dir / (jobs == 1 ? "r1.h5" : "r2.h5")).string() +
                                        " --jsonl " + jsonl.string());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    std::ifstream in(jsonl);
    std::string line;
    ASSERT_TRUE(std::getline(in, line));
    work[jobs - 1] = nlohmann::json::parse(line)["result"]["work"];
  }
  for (const char* k : {"modal_solves", "prony_decompositions", "ffts", "reduced_port_models"})
    EXPECT_EQ(work[0].value(k, -1L), work[1].value(k, -1L)) << k;
  ASSERT_EQ(work[0]["phases"].size(), work[1]["phases"].size());
  for (std::size_t i = 0; i < work[0]["phases"].size(); ++i)
    for (const char* k : {"modal_solves", "ffts"})
      EXPECT_EQ(work[0]["phases"][i][k], work[1]["phases"][i][k]) << work[0]["phases"][i]["phase"] << " " << k;
  fs::remove_all(dir);
}

}  // namespace
