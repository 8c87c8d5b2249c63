// piezo-replay/1 results files: every field round-trips, a key is replaced
// as one unit, records copy between files, and files of other kinds are
// refused with a message naming the file and what is wrong.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

#include "acquisition/capture_file.hpp"
#include "acquisition/results_file.hpp"
#include "tests/support/capture_mutations.hpp"

using namespace piezo;
namespace fs = std::filesystem;

namespace {
fs::path tmp(const std::string& name) {
  auto d = fs::temp_directory_path() / ("piezobench-results-" + std::to_string(::getpid()));
  fs::create_directories(d);
  fs::remove(d / name);
  return d / name;
}

acq::ResultRecord sample(const std::string& key, const std::string& status) {
  acq::ResultRecord r;
  r.key = key;
  r.input_path = "line 1/T-001.h5";
  r.sha256 = "ab12";
  r.status = status;
  r.result_json = R"({"status":")" + status + R"(","µ":"UTF-8 ✓"})";
  r.elapsed_s = 0.25;
  r.replayed_utc = "2026-01-02T03:04:05Z";
  r.curves.push_back(
      {"measured (Prony-SS)", {100.0, 200.0, 300.0}, {{1.0, -2.0}, {3.0, -4.0}, {5.5, 6.5}}});
  r.curves.push_back({"updated model", {100.0}, {{7.0, 8.0}}});
  return r;
}
}  // namespace

TEST(ResultsFile, RoundTripOfEveryField) {
  const auto f = tmp("a.h5");
  {
    auto rf = acq::ResultsFile::open_or_create(f, "test");
    rf.put(sample("k1", "ok"));
    rf.put(sample("k0", "failed"));
    auto idx = rf.index();
    ASSERT_EQ(idx.size(), 2u);
    EXPECT_EQ(idx[0].key, "k0");
    EXPECT_EQ(idx[0].status, "failed");
    EXPECT_EQ(idx[1].input_path, "line 1/T-001.h5");
    EXPECT_FALSE(rf.get("nope").has_value());
  }
  std::vector<acq::ResultRecord> got;
  acq::for_each_result(f, [&](const acq::ResultRecord& r) { got.push_back(r); }, {true});
  ASSERT_EQ(got.size(), 2u);
  const auto want = sample("k1", "ok");
  const auto& r = got[1];
  EXPECT_EQ(r.key, "k1");
  EXPECT_EQ(r.input_path, want.input_path);
  EXPECT_EQ(r.sha256, want.sha256);
  EXPECT_EQ(r.status, "ok");
  EXPECT_EQ(r.result_json, want.result_json);
  EXPECT_EQ(r.elapsed_s, 0.25);
  EXPECT_EQ(r.replayed_utc, want.replayed_utc);
  ASSERT_EQ(r.curves.size(), 2u);
  for (int c = 0; c < 2; ++c) {
    EXPECT_EQ(r.curves[c].label, want.curves[c].label);
    EXPECT_EQ(r.curves[c].f_hz, want.curves[c].f_hz);
    EXPECT_EQ(r.curves[c].z_ohm, want.curves[c].z_ohm);
  }
  // Without curves: the same record, no curve data read.
  acq::for_each_result(f, [&](const acq::ResultRecord& x) { EXPECT_TRUE(x.curves.empty()); });
}

TEST(ResultsFile, ReopenReplaceRemoveAndCopy) {
  const auto f = tmp("b.h5"), g = tmp("c.h5");
  {
    auto rf = acq::ResultsFile::open_or_create(f, "test");
    rf.put(sample("k0", "failed"));
    rf.put(sample("k1", "ok"));
  }
  {
    auto rf = acq::ResultsFile::open_or_create(f, "test");  // resumed: records kept
    ASSERT_EQ(rf.index().size(), 2u);
    auto again = sample("k0", "ok");
    again.curves.clear();
    rf.put(again);  // replaces the failed record as a whole
    auto r = rf.get("k0", {true});
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, "ok");
    EXPECT_TRUE(r->curves.empty());
    rf.remove("k1");
    EXPECT_EQ(rf.index().size(), 1u);
    EXPECT_THROW(rf.put(sample("bad/key", "ok")), std::invalid_argument);
  }
  {
    auto out = acq::ResultsFile::create(g, "merge");
    out.copy_from(f, {"k0"});
    EXPECT_THROW(out.copy_from(f, {"k1"}), acq::ResultsError);  // removed above
    auto r = out.get("k0");
    ASSERT_TRUE(r);
    EXPECT_EQ(r->result_json, sample("k0", "ok").result_json);
  }
  EXPECT_THROW(acq::ResultsFile::create(g, "x"), acq::ResultsError);  // exists
}

TEST(ResultsFile, OtherFilesAreRefusedWithTheirName) {
  const auto cap = tmp("capture.h5");
  acq::write_capture(cap, test::small_valid_capture(64));
  for (const auto& f : {cap, fs::path("/no/such/results.h5")}) {
    try {
      acq::for_each_result(f, [](const acq::ResultRecord&) {});
      FAIL() << "expected an error for " << f;
    } catch (const acq::ResultsError& e) {
      EXPECT_NE(std::string(e.what()).find(f.string()), std::string::npos) << e.what();
    }
  }
  try {
    acq::ResultsFile::open_or_create(cap, "x");
    FAIL() << "a capture must not be opened as results";
  } catch (const acq::ResultsError& e) {
    EXPECT_NE(std::string(e.what()).find("\"piezo-capture\", expected \"piezo-replay\""),
              std::string::npos)
        << e.what();
  }
}
